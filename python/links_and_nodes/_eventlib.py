"""ctypes declarations of libln's event functions (docs/events.md), each declared once;
those returning an LN_E* code raise the exception class of that code."""

from __future__ import annotations

import ctypes

from ._clientlib import _check
from ._libln import _declare

c_char_p, c_double, c_int, c_size_t, c_uint64, c_void_p = (
    ctypes.c_char_p, ctypes.c_double, ctypes.c_int, ctypes.c_size_t, ctypes.c_uint64,
    ctypes.c_void_p)


class EventResult(ctypes.Structure):
    """struct ln_event_result."""

    _fields_ = [("handler", c_char_p), ("client", c_char_p), ("code", c_int),
                ("error", c_char_p), ("connect", c_void_p), ("reply", c_void_p)]


# int handler(ln_client*, ln_event_request*, void* user_data); ctypes takes the GIL for it.
EVENT_HANDLER = ctypes.CFUNCTYPE(c_int, c_void_p, c_void_p, c_void_p)
# int filter(const void* connect, void* user_data)
EVENT_FILTER = ctypes.CFUNCTYPE(c_int, c_void_p, c_void_p)

ln_event_connect = _declare("ln_event_connect", c_int, [
    c_void_p, ctypes.POINTER(c_void_p), c_char_p, c_char_p, c_uint64, c_char_p, c_void_p,
    EVENT_HANDLER, c_void_p, c_char_p], _check)
ln_event_disconnect = _declare("ln_event_disconnect", c_int, [c_void_p], _check)
ln_event_handler_name = _declare("ln_event_handler_name", c_char_p, [c_void_p])
ln_event_request_get_data = _declare("ln_event_request_get_data", c_int, [c_void_p, c_void_p],
                                     _check)
ln_event_request_reply = _declare("ln_event_request_reply", c_int, [c_void_p, c_void_p], _check)
ln_event_request_reply_error = _declare("ln_event_request_reply_error", c_int,
                                        [c_void_p, c_char_p], _check)
ln_get_event = _declare("ln_get_event", c_int, [
    c_void_p, ctypes.POINTER(c_void_p), c_char_p, c_char_p, c_uint64, c_char_p], _check)
ln_event_set_filter = _declare("ln_event_set_filter", c_int, [c_void_p, EVENT_FILTER, c_void_p],
                               _check)
ln_event_call = _declare("ln_event_call", c_int, [c_void_p, c_void_p, c_double], _check)
ln_event_result_count = _declare("ln_event_result_count", c_int, [c_void_p], _check)
ln_event_get_result = _declare("ln_event_get_result", c_int,
                               [c_void_p, c_size_t, ctypes.POINTER(EventResult)], _check)
ln_event_release = _declare("ln_event_release", c_int, [c_void_p], _check)
