"""Private ctypes layer over libln: finds and loads the library, declares every C function
once (argtypes, restype, errcheck), checks the library version against the package's and
builds the exception classes from libln's error table.  Public modules sit on top of this."""

import ctypes
import functools
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


_declare = functools.partial(_native.declare, lib)


ln_strerror = _declare("ln_strerror", ctypes.c_char_p, [ctypes.c_int])
ln_error_name = _declare("ln_error_name", ctypes.c_char_p, [ctypes.c_int])
ln_error_count = _declare("ln_error_count", ctypes.c_int, [])
ln_version = _declare("ln_version", ctypes.c_char_p, [])
ln_version_check = _declare("ln_version_check", ctypes.c_int, [ctypes.c_int, ctypes.c_int],
                            _check)


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
