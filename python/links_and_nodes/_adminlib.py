"""ctypes declarations of libln's internal API (libln/src/ln_admin.h) for the manager and the
tests: topic segment administration (ln_ring_admin_*), ring taps (ln_ring_tap_*) and the host
id.  libln.so does not export them: they come from libln_admin.so, the manager's private build
of the same sources, loaded from links_and_nodes/ next to the libln.so.1 that _libln loaded
(docs/building.md).  That library has its own last error, so its functions raise with
last_error() of this module as detail, and failures are explained by this last_error()."""

from __future__ import annotations

import ctypes
import functools
from typing import Any

from . import _libln, _native
from ._clientlib import SampleInfo
from ._libln import error_from_code

c_char_p, c_double, c_int, c_uint32, c_uint64, c_void_p = (
    ctypes.c_char_p, ctypes.c_double, ctypes.c_int, ctypes.c_uint32, ctypes.c_uint64,
    ctypes.c_void_p)

FILE = "links_and_nodes/libln_admin.so"  # relative to the directory of libln.so.1

lib = _native.load_beside(_libln.lib, "ln_version", FILE, "libln_admin.so")

ln_last_error = lib.ln_last_error
ln_last_error.restype = c_char_p
ln_last_error.argtypes = []


def last_error() -> str:
    """The last error text of this thread's admin calls (not of libln.so's calls)."""
    text = ln_last_error()
    return text.decode("utf-8", "replace") if text else ""


def _check(result: int, func: Any, args: tuple[Any, ...]) -> int:
    """errcheck for functions returning an ln_error: raise the class of a negative code."""
    if result < 0:
        raise error_from_code(result, last_error() or f"{func.__name__}{args}")
    return result


_declare = functools.partial(_native.declare, lib)


# ---- topic segment administration (ln_manager) ------------------------------------------
# A handle from ln_ring_admin_create maps only the segment's header and is freed by
# ln_ring_admin_close; the segment itself lives until ln_ring_admin_unlink.
class RingAdmin(ctypes.Structure):
    """Opaque struct ln_ring_admin; only pointers to it cross the boundary."""


RingAdminHandle = ctypes.POINTER(RingAdmin)


class RingInfo(ctypes.Structure):
    """struct ln_ring_info: what a segment's header says (ln_ring_admin_info)."""

    _fields_ = [("topic", ctypes.c_char * 256), ("md_name", ctypes.c_char * 256),
                ("successor", ctypes.c_char * 256), ("layout_hash", c_uint64),
                ("message_size", c_uint64), ("write_seq", c_uint64),
                ("active_readers", c_uint64), ("slot_count", c_uint32),
                ("retired", c_uint32), ("publishers", c_uint32), ("subscribers", c_uint32)]


ln_ring_admin_create = _declare("ln_ring_admin_create", c_int, [
    ctypes.POINTER(RingAdminHandle), c_char_p, c_char_p, c_char_p, c_uint64, c_uint64,
    c_uint32], _check)
ln_ring_admin_open = _declare("ln_ring_admin_open", c_int, [
    ctypes.POINTER(RingAdminHandle), c_char_p], _check)
ln_ring_admin_close = _declare("ln_ring_admin_close", None, [RingAdminHandle])
ln_ring_admin_unlink = _declare("ln_ring_admin_unlink", c_int, [c_char_p], _check)
ln_ring_admin_set_counts = _declare("ln_ring_admin_set_counts", c_int, [
    RingAdminHandle, c_uint32, c_uint32], _check)
ln_ring_admin_write_seq = _declare("ln_ring_admin_write_seq", c_int, [
    RingAdminHandle, ctypes.POINTER(c_uint64)], _check)
ln_ring_admin_info = _declare("ln_ring_admin_info", c_int, [
    RingAdminHandle, ctypes.POINTER(RingInfo)], _check)
ln_ring_admin_reserve_reader = _declare("ln_ring_admin_reserve_reader", c_int, [
    RingAdminHandle, c_uint32, ctypes.c_int32, c_uint32], _check)
ln_ring_admin_release_reader = _declare("ln_ring_admin_release_reader", c_int, [
    RingAdminHandle, c_uint32], _check)
ln_ring_admin_retire = _declare("ln_ring_admin_retire", c_int, [
    RingAdminHandle, RingAdminHandle, c_char_p, c_double], _check)
ln_ring_admin_purge_instance = _declare("ln_ring_admin_purge_instance", c_int, [c_char_p],
                                        _check)
ln_ring_segment_size = _declare("ln_ring_segment_size", c_uint64, [c_uint64, c_uint32])

# ---- ring taps (ln_daemon's forwarding; for tests and tools) -----------------------------
LN_TAP_EVERY = 0
LN_TAP_NEWEST = 1
ln_ring_tap_open = _declare("ln_ring_tap_open", c_int, [
    ctypes.POINTER(c_void_p), c_char_p, c_uint64, c_uint64, ctypes.c_uint], _check)
ln_ring_tap_close = _declare("ln_ring_tap_close", None, [c_void_p])
ln_ring_tap_read = _declare("ln_ring_tap_read", c_int, [
    c_void_p, c_void_p, ctypes.POINTER(SampleInfo), c_double], _check)
ln_ring_tap_inject = _declare("ln_ring_tap_inject", c_int, [
    c_void_p, c_void_p, c_uint64, ctypes.c_int64], _check)
ln_ring_tap_write_seq = _declare("ln_ring_tap_write_seq", c_uint64, [c_void_p])
ln_ring_tap_segment = _declare("ln_ring_tap_segment", c_char_p, [c_void_p])

# ---- host id -----------------------------------------------------------------------------
ln_host_id = _declare("ln_host_id", None, [c_char_p, ctypes.c_size_t])


def host_id() -> str:
    """This host's identity as libln reports it to the manager ($LN_HOST_ID, else
    hostname/boot_id)."""
    buf = ctypes.create_string_buffer(256)
    ln_host_id(buf, len(buf))
    return buf.value.decode("utf-8", "replace")
