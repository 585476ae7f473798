"""Private ctypes layer over libln: finds and loads the library, declares every C function
once (argtypes, restype, errcheck), checks the library version against the package's and
builds the exception classes from libln's error table.  Public modules sit on top of this."""

import ctypes
from collections.abc import Callable
from typing import Any

from . import __version__, _native
from .errors import LnError, make_error_classes

SONAME = "libln.so.1"
ENV_OVERRIDE = "LN_LIBRARY_PATH"  # a library file, or a directory holding libln.so.1


lib = _native.load(SONAME, ENV_OVERRIDE, "libln", "libln")


def _check(result: int, func: Any, args: tuple[Any, ...]) -> int:
    """errcheck for functions returning an ln_error: raise the class of a negative code."""
    if result < 0:
        raise error_from_code(result, f"{func.__name__}{args}")
    return result


def _declare(name: str, restype: Any, argtypes: list[Any],
             errcheck: Callable[..., Any] | None = None) -> Any:
    func = getattr(lib, name)
    func.restype = restype
    func.argtypes = argtypes
    if errcheck is not None:
        func.errcheck = errcheck
    return func


ln_strerror = _declare("ln_strerror", ctypes.c_char_p, [ctypes.c_int])
ln_error_name = _declare("ln_error_name", ctypes.c_char_p, [ctypes.c_int])
ln_error_count = _declare("ln_error_count", ctypes.c_int, [])
ln_version = _declare("ln_version", ctypes.c_char_p, [])
ln_version_check = _declare("ln_version_check", ctypes.c_int, [ctypes.c_int, ctypes.c_int],
                            _check)


# ---- topic segment administration (ln_manager) ------------------------------------------
# A handle from ln_ring_admin_create maps only the segment's header and is freed by
# ln_ring_admin_close; the segment itself lives until ln_ring_admin_unlink.
class RingAdmin(ctypes.Structure):
    """Opaque struct ln_ring_admin; only pointers to it cross the boundary."""


RingAdminHandle = ctypes.POINTER(RingAdmin)

ln_ring_admin_create = _declare("ln_ring_admin_create", ctypes.c_int, [
    ctypes.POINTER(RingAdminHandle), ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p,
    ctypes.c_uint64, ctypes.c_uint64, ctypes.c_uint32], _check)
ln_ring_admin_close = _declare("ln_ring_admin_close", None, [RingAdminHandle])
ln_ring_admin_unlink = _declare("ln_ring_admin_unlink", ctypes.c_int, [ctypes.c_char_p],
                                _check)
ln_ring_admin_set_counts = _declare("ln_ring_admin_set_counts", ctypes.c_int, [
    RingAdminHandle, ctypes.c_uint32, ctypes.c_uint32], _check)
ln_ring_admin_write_seq = _declare("ln_ring_admin_write_seq", ctypes.c_int, [
    RingAdminHandle, ctypes.POINTER(ctypes.c_uint64)], _check)
ln_ring_admin_reserve_reader = _declare("ln_ring_admin_reserve_reader", ctypes.c_int, [
    RingAdminHandle, ctypes.c_uint32, ctypes.c_int32, ctypes.c_uint32], _check)
ln_ring_admin_release_reader = _declare("ln_ring_admin_release_reader", ctypes.c_int, [
    RingAdminHandle, ctypes.c_uint32], _check)
ln_ring_admin_retire = _declare("ln_ring_admin_retire", ctypes.c_int, [
    RingAdminHandle, RingAdminHandle, ctypes.c_char_p, ctypes.c_double], _check)
ln_ring_admin_purge_instance = _declare("ln_ring_admin_purge_instance", ctypes.c_int,
                                        [ctypes.c_char_p], _check)
ln_ring_admin_open = _declare("ln_ring_admin_open", ctypes.c_int, [
    ctypes.POINTER(RingAdminHandle), ctypes.c_char_p], _check)


class RingInfo(ctypes.Structure):
    """struct ln_ring_info: what a segment's header says (ln_ring_admin_info)."""

    _fields_ = [("topic", ctypes.c_char * 256), ("md_name", ctypes.c_char * 256),
                ("successor", ctypes.c_char * 256), ("layout_hash", ctypes.c_uint64),
                ("message_size", ctypes.c_uint64), ("write_seq", ctypes.c_uint64),
                ("active_readers", ctypes.c_uint64), ("slot_count", ctypes.c_uint32),
                ("retired", ctypes.c_uint32), ("publishers", ctypes.c_uint32),
                ("subscribers", ctypes.c_uint32)]


ln_ring_admin_info = _declare("ln_ring_admin_info", ctypes.c_int, [
    RingAdminHandle, ctypes.POINTER(RingInfo)], _check)
ln_ring_segment_size = _declare("ln_ring_segment_size", ctypes.c_uint64,
                                [ctypes.c_uint64, ctypes.c_uint32])
ln_host_id = _declare("ln_host_id", None, [ctypes.c_char_p, ctypes.c_size_t])


def host_id() -> str:
    """This host's identity as libln reports it to the manager ($LN_HOST_ID, else
    hostname/boot_id)."""
    buf = ctypes.create_string_buffer(256)
    ln_host_id(buf, len(buf))
    return buf.value.decode("utf-8", "replace")


def _read_table() -> list[tuple[int, str, str]]:
    """(code, name, text) of every error entry; codes run from -1 to -ln_error_count()."""
    table = []
    for code in range(-1, -ln_error_count() - 1, -1):
        name = ln_error_name(code)
        if name is None:
            raise ImportError(f"libln error table has a gap at code {code}")
        table.append((code, name.decode(), ln_strerror(code).decode()))
    return table


ERRORS_BY_CODE: dict[int, type[LnError]] = make_error_classes(_read_table())
ERROR_CLASSES: dict[str, type[LnError]] = {
    cls.__name__: cls for cls in ERRORS_BY_CODE.values()}


def error_from_code(code: int, detail: str | None = None) -> LnError:
    """The exception for an ln_error code; an unknown code gives a plain LnError."""
    cls = ERRORS_BY_CODE.get(code)
    if cls is not None:
        return cls(detail)
    error = LnError(f"unknown libln error code {code}" + (f": {detail}" if detail else ""))
    error.code = code
    return error


def _check_version() -> None:
    major, minor = (int(part) for part in __version__.split(".")[:2])
    library = ln_version().decode()
    try:
        ln_version_check(major, minor)
    except LnError as exc:
        raise ImportError(f"libln {library} at {lib._name} cannot serve links_and_nodes "
                          f"{__version__}") from exc


_check_version()
