"""ctypes declarations of libln's client, topic and service functions (each C function
declared once).

Functions that return an LN_E* code get an errcheck that raises the exception class of
that code with libln's thread-local last-error text as detail.
"""

from __future__ import annotations

import ctypes
from typing import Any

from ._libln import ERRORS_BY_CODE, _declare, error_from_code

c_double, c_int, c_size_t, c_uint32, c_uint64 = (
    ctypes.c_double, ctypes.c_int, ctypes.c_size_t, ctypes.c_uint32, ctypes.c_uint64)
c_char_p, c_void_p = ctypes.c_char_p, ctypes.c_void_p


class ClientOptions(ctypes.Structure):
    _fields_ = [("manager", c_char_p), ("argc", c_int), ("argv", ctypes.POINTER(c_char_p)),
                ("timeout", c_double), ("flags", c_uint32)]


class PortOptions(ctypes.Structure):
    _fields_ = [("buffers", c_uint32), ("flags", c_uint32), ("spin_us", c_uint32)]


class SampleInfo(ctypes.Structure):
    _fields_ = [("seq", c_uint64), ("timestamp_ns", ctypes.c_int64), ("overruns", c_uint64)]


ln_last_error = _declare("ln_last_error", c_char_p, [])


def last_error() -> str:
    text = ln_last_error()
    return text.decode("utf-8", "replace") if text else ""


def _check(result: int, func: Any, args: tuple[Any, ...]) -> int:
    if result < 0:
        raise error_from_code(result, last_error())
    return result


def _error_code(name: str) -> int:
    """The code of LN_<name> in libln's error table (as loaded: _libln.ERRORS_BY_CODE)."""
    code = next((code for code, cls in ERRORS_BY_CODE.items() if cls.name == name), None)
    if code is None:
        raise ImportError(f"libln's error table has no LN_{name}")
    return code


LN_EAGAIN = _error_code("EAGAIN")
LN_ETIMEOUT = _error_code("ETIMEOUT")
LN_EOVERRUN = _error_code("EOVERRUN")
LN_PUBLISH_WAIT_FOR_SUBSCRIBERS = 0x1
LN_CLIENT_NO_RECONNECT = 0x1
LN_SUBSCRIBE_UDP = 0x100
LN_SUBSCRIBE_TCP = 0x200

ln_client_options_init = _declare("ln_client_options_init", None, [ctypes.POINTER(ClientOptions)])
ln_client_create = _declare("ln_client_create", c_int, [ctypes.POINTER(c_void_p), c_char_p,
                                                         ctypes.POINTER(ClientOptions)], _check)
ln_client_destroy = _declare("ln_client_destroy", c_int, [c_void_p], _check)
ln_client_name = _declare("ln_client_name", c_char_p, [c_void_p])
ln_client_last_error = _declare("ln_client_last_error", c_int, [c_void_p, c_char_p, c_size_t])
ln_port_options_init = _declare("ln_port_options_init", None, [ctypes.POINTER(PortOptions)])
_port_args = [c_void_p, ctypes.POINTER(c_void_p), c_char_p, c_char_p, c_uint64, c_size_t,
              ctypes.POINTER(PortOptions)]
ln_publish = _declare("ln_publish", c_int, _port_args, _check)
ln_subscribe = _declare("ln_subscribe", c_int, _port_args, _check)
ln_unpublish = _declare("ln_unpublish", c_int, [c_void_p], _check)
ln_unsubscribe = _declare("ln_unsubscribe", c_int, [c_void_p], _check)
ln_write = _declare("ln_write", c_int, [c_void_p, c_void_p, c_size_t, c_double], _check)
ln_write_loan = _declare("ln_write_loan", c_int, [c_void_p, ctypes.POINTER(c_void_p), c_double],
                         _check)
ln_write_commit = _declare("ln_write_commit", c_int, [c_void_p], _check)
ln_write_abort = _declare("ln_write_abort", c_int, [c_void_p], _check)
# Reads return timeouts as values (None in Python), so they are checked by the caller.
ln_read = _declare("ln_read", c_int, [c_void_p, c_void_p, c_size_t, c_double,
                                      ctypes.POINTER(SampleInfo)])
ln_read_borrow = _declare("ln_read_borrow", c_int, [c_void_p, ctypes.POINTER(c_void_p), c_double,
                                                    ctypes.POINTER(SampleInfo)])
ln_read_release = _declare("ln_read_release", c_int, [c_void_p])
# After set_interruptible a signal ends a blocking read with LN_EINTR (the bindings run
# Python's handlers and read on); ln_inport_interrupt wakes a read from another thread.
ln_inport_set_interruptible = _declare("ln_inport_set_interruptible", c_int, [c_void_p, c_int],
                                       _check)
ln_inport_interrupt = _declare("ln_inport_interrupt", c_int, [c_void_p], _check)
ln_client_use_clock = _declare("ln_client_use_clock", c_int, [c_void_p, c_char_p], _check)
ln_now = _declare("ln_now", c_int, [c_void_p, ctypes.POINTER(ctypes.c_int64)], _check)
ln_outport_subscriber_count = _declare("ln_outport_subscriber_count", c_int, [c_void_p], _check)
ln_inport_publisher_count = _declare("ln_inport_publisher_count", c_int, [c_void_p], _check)
ln_inport_overruns = _declare("ln_inport_overruns", c_uint64, [c_void_p])

# ---- manager commands (ln_control; loggers use it) -----------------------------------------
ln_control = _declare("ln_control", c_int, [c_void_p, c_char_p, ctypes.POINTER(c_void_p)],
                      _check)
ln_free = _declare("ln_free", None, [c_void_p])

# ---- client logging (ln.LogHandler); ln_log_text's LN_EAGAIN (dropped) is no exception ----
ln_log_text = _declare("ln_log_text", c_int, [c_void_p, c_int, c_char_p, c_int, c_char_p,
                                              c_char_p])
ln_log_set_level = _declare("ln_log_set_level", c_int, [c_void_p, c_int], _check)
ln_log_counts = _declare("ln_log_counts", c_int, [c_void_p, ctypes.POINTER(c_uint64),
                                                  ctypes.POINTER(c_uint64)], _check)
ln_log_flush = _declare("ln_log_flush", c_int, [c_void_p, ctypes.c_double], _check)

# ---- services ----------------------------------------------------------------------------
LN_EINTR = _error_code("EINTR")
# int handler(ln_client*, ln_service_request*, void* user_data); ctypes takes the GIL for it,
# so libln's pool threads may run Python handlers.
SERVICE_HANDLER = ctypes.CFUNCTYPE(c_int, c_void_p, c_void_p, c_void_p)

ln_get_service = _declare("ln_get_service", c_int, [
    c_void_p, ctypes.POINTER(c_void_p), c_char_p, c_char_p, c_uint64, c_char_p], _check)
ln_service_call = _declare("ln_service_call", c_int, [c_void_p, c_void_p, c_void_p, c_double],
                           _check)
ln_service_set_max_size = _declare("ln_service_set_max_size", c_int, [c_void_p, c_size_t], _check)
ln_service_release = _declare("ln_service_release", c_int, [c_void_p], _check)
ln_get_service_provider = _declare("ln_get_service_provider", c_int, [
    c_void_p, ctypes.POINTER(c_void_p), c_char_p, c_char_p, c_uint64, c_char_p], _check)
ln_service_provider_set_handler = _declare("ln_service_provider_set_handler", c_int,
                                           [c_void_p, SERVICE_HANDLER, c_void_p], _check)
ln_service_provider_set_max_size = _declare("ln_service_provider_set_max_size", c_int,
                                            [c_void_p, c_size_t], _check)
ln_service_provider_register = _declare("ln_service_provider_register", c_int,
                                        [c_void_p, c_char_p], _check)
ln_unregister_service_provider = _declare("ln_unregister_service_provider", c_int, [c_void_p],
                                          _check)
# Returns the number of requests handled; LN_EINTR is checked by the caller.
ln_wait_and_handle_service_group_requests = _declare(
    "ln_wait_and_handle_service_group_requests", c_int, [c_void_p, c_char_p, c_double])
ln_handle_service_group_in_thread_pool = _declare(
    "ln_handle_service_group_in_thread_pool", c_int, [c_void_p, c_char_p, c_char_p], _check)
ln_set_max_threads = _declare("ln_set_max_threads", c_int, [c_void_p, c_char_p, ctypes.c_uint],
                              _check)
ln_service_request_get_data = _declare("ln_service_request_get_data", c_int,
                                       [c_void_p, c_void_p], _check)
ln_service_request_respond = _declare("ln_service_request_respond", c_int, [c_void_p, c_void_p],
                                      _check)
ln_service_request_respond_error = _declare("ln_service_request_respond_error", c_int,
                                            [c_void_p, c_char_p], _check)
ln_service_request_service_name = _declare("ln_service_request_service_name", c_char_p,
                                           [c_void_p])
