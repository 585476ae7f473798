"""Finds and loads the project's shared objects (libln, libln_pull) for the ctypes layers:
an explicit path from the environment wins and is never silently replaced; else the copy a
wheel carries inside the package (bundled.py); else the checkout's release build; else the
system loader (ld.so.cache, LD_LIBRARY_PATH, /usr/lib).
A private library (the manager's libln_admin.so) is loaded from a directory next to the
library it belongs to, wherever that one was found."""

import ctypes
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from . import bundled
from .errors import LibraryNotFoundError


def candidates(soname: str, env_override: str, build_dir: str) -> Iterator[str]:
    """Where to look for `soname`: $env_override (a file, or a directory holding it), then
    lib/ of an installed wheel, then build/release/`build_dir` of the checkout, then the
    system loader."""
    override = os.environ.get(env_override)
    if override:
        yield str(Path(override) / soname) if Path(override).is_dir() else override
        return
    in_package = bundled.shared_object(soname)
    if in_package is not None:
        yield str(in_package)
        return
    checkout = Path(__file__).resolve().parents[2]  # python/links_and_nodes/ -> checkout
    in_tree = checkout / "build" / "release" / build_dir / soname
    if in_tree.exists():
        yield str(in_tree)
    yield soname


def load(soname: str, env_override: str, build_dir: str, label: str) -> ctypes.CDLL:
    """The first candidate that loads; LibraryNotFoundError naming every attempt."""
    failures = []
    for candidate in candidates(soname, env_override, build_dir):
        try:
            return ctypes.CDLL(candidate)
        except OSError as exc:
            failures.append(f"{candidate}: {exc}")
    raise LibraryNotFoundError(f"cannot load {label} (" + "; ".join(failures)
                               + f"); build it with `scons` or set {env_override}")


class _DlInfo(ctypes.Structure):
    """Dl_info of dladdr(3)."""

    _fields_ = [("dli_fname", ctypes.c_char_p), ("dli_fbase", ctypes.c_void_p),
                ("dli_sname", ctypes.c_char_p), ("dli_saddr", ctypes.c_void_p)]


def _dladdr() -> Any:
    """dladdr(3): in libc since glibc 2.34, in libdl before."""
    for name in (None, "libdl.so.2"):
        try:
            func = getattr(ctypes.CDLL(name), "dladdr", None)
        except OSError:
            continue
        if func is not None:
            func.restype = ctypes.c_int
            func.argtypes = [ctypes.c_void_p, ctypes.POINTER(_DlInfo)]
            return func
    raise LibraryNotFoundError("dladdr() is not available")


def file_of(lib: ctypes.CDLL, symbol: str) -> Path:
    """The file `lib` was loaded from (the one holding `symbol`), however it was found."""
    info = _DlInfo()
    if not _dladdr()(ctypes.cast(getattr(lib, symbol), ctypes.c_void_p), ctypes.byref(info)) \
            or not info.dli_fname:
        raise LibraryNotFoundError(f"cannot tell where {lib._name} was loaded from")
    return Path(os.fsdecode(info.dli_fname)).resolve()


def load_beside(owner: ctypes.CDLL, symbol: str, relative: str, label: str) -> ctypes.CDLL:
    """The private library at `relative` to the directory of `owner` (located through its
    `symbol`): for libln_admin.so, links_and_nodes/ next to libln.so.1, in the build tree as
    installed (docs/building.md)."""
    path = file_of(owner, symbol).parent / relative
    try:
        return ctypes.CDLL(str(path))
    except OSError as exc:
        raise LibraryNotFoundError(f"cannot load {label} ({path}: {exc}); build it with "
                                   "`scons`, or install it with libln (`scons install`, "
                                   "Debian's libln1)") from exc


def declare(lib: ctypes.CDLL, name: str, restype: Any, argtypes: list[Any],
            errcheck: Any = None) -> Any:
    """Function `name` of `lib` with its result and argument types (and errcheck) set."""
    func = getattr(lib, name)
    func.restype = restype
    func.argtypes = argtypes
    if errcheck is not None:
        func.errcheck = errcheck
    return func
