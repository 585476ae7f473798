"""Finds and loads the project's shared objects (libln, libln_pull) for the ctypes layers:
an explicit path from the environment wins and is never silently replaced; else the
checkout's release build; else the system loader (ld.so.cache, LD_LIBRARY_PATH, /usr/lib)."""

import ctypes
import os
from collections.abc import Iterator
from pathlib import Path

from .errors import LibraryNotFoundError


def candidates(soname: str, env_override: str, build_dir: str) -> Iterator[str]:
    """Where to look for `soname`: $env_override (a file, or a directory holding it), then
    build/release/`build_dir` of the checkout, then the system loader."""
    override = os.environ.get(env_override)
    if override:
        yield str(Path(override) / soname) if Path(override).is_dir() else override
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
