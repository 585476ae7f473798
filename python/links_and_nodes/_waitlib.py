"""ctypes declarations of libln's waitset functions (ln.h, "waiting on many things: the
waitset"), each declared once, with the errcheck of _clientlib (raise the class of a negative
code); ln_waitset_wait returns LN_EINTR as a value, for the caller to wait again."""

from __future__ import annotations

import ctypes

from ._clientlib import _check
from ._libln import _declare

c_double, c_int, c_int64, c_size_t, c_uint32 = (
    ctypes.c_double, ctypes.c_int, ctypes.c_int64, ctypes.c_size_t, ctypes.c_uint32)
c_char_p, c_void_p = ctypes.c_char_p, ctypes.c_void_p

# enum ln_waitset_kind
LN_WAIT_DATA = 1
LN_WAIT_DEADLINE = 2
LN_WAIT_GONE = 3
LN_WAIT_BACK = 4
LN_WAIT_REQUESTS = 5
LN_WAIT_PARAMETERS = 6
LN_WAIT_FD = 7
LN_WAIT_TIMER = 8
LN_WAIT_TRIGGER = 9
# inport conditions; file descriptor conditions and what fired
LN_WAIT_ON_DATA = 0x1
LN_WAIT_ON_LIVELINESS = 0x2
LN_WAIT_READABLE = 0x1
LN_WAIT_WRITABLE = 0x2
LN_WAIT_ERROR = 0x4
LN_WAITSET_MAX_ATTACHMENTS = 65535
LN_WAITSET_TRIGGER_ID = 0


class WaitsetEvent(ctypes.Structure):
    _fields_ = [("id", c_uint32), ("kind", c_uint32), ("events", c_uint32), ("count", c_uint32),
                ("user_data", c_void_p)]


_out_id = ctypes.POINTER(c_uint32)

ln_waitset_create = _declare("ln_waitset_create", c_int, [ctypes.POINTER(c_void_p)], _check)
ln_waitset_destroy = _declare("ln_waitset_destroy", c_int, [c_void_p], _check)
ln_waitset_attach_inport = _declare("ln_waitset_attach_inport", c_int,
                                    [c_void_p, c_void_p, c_uint32, c_double, c_void_p, _out_id],
                                    _check)
ln_waitset_set_deadline = _declare("ln_waitset_set_deadline", c_int,
                                   [c_void_p, c_uint32, c_double], _check)
ln_waitset_attach_service_group = _declare("ln_waitset_attach_service_group", c_int,
                                           [c_void_p, c_void_p, c_char_p, c_void_p, _out_id],
                                           _check)
ln_waitset_attach_provider = _declare("ln_waitset_attach_provider", c_int,
                                      [c_void_p, c_void_p, c_void_p, _out_id], _check)
ln_waitset_attach_event_handler = _declare("ln_waitset_attach_event_handler", c_int,
                                           [c_void_p, c_void_p, c_void_p, _out_id], _check)
ln_waitset_attach_parameter_block = _declare("ln_waitset_attach_parameter_block", c_int,
                                             [c_void_p, c_void_p, c_void_p, _out_id], _check)
ln_waitset_attach_fd = _declare("ln_waitset_attach_fd", c_int,
                                [c_void_p, c_int, c_uint32, c_void_p, _out_id], _check)
ln_waitset_attach_timer = _declare("ln_waitset_attach_timer", c_int,
                                   [c_void_p, c_int64, c_double, c_void_p, _out_id], _check)
ln_waitset_detach = _declare("ln_waitset_detach", c_int, [c_void_p, c_uint32], _check)
# Returns how many events it wrote, or LN_EINTR / another code: checked by the caller.
ln_waitset_wait = _declare("ln_waitset_wait", c_int,
                           [c_void_p, c_double, ctypes.POINTER(WaitsetEvent), c_size_t])
ln_waitset_trigger = _declare("ln_waitset_trigger", c_int, [c_void_p], _check)
ln_waitset_fd = _declare("ln_waitset_fd", c_int, [c_void_p], _check)
ln_waitset_next_due = _declare("ln_waitset_next_due", c_int,
                               [c_void_p, ctypes.POINTER(c_int64)], _check)
