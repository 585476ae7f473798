"""Shared setup of the Python tests: import the source tree, not an installed copy; mark each
test by what it runs; and the `netlab` fixture, so that any test can ask for emulated hosts.

`ln_generate` lives at the repository root and `links_and_nodes` under `python/`; both go
first on sys.path so the tests run from a plain checkout, and so does this directory, for the
modules every test package shares (polling.py, netlab.py).

Markers (tests/README.md): every test is marked at collection from what its code reaches
(marking.py), never by hand.  `integration`: it starts a process (subprocess, asyncio's
subprocesses, os.fork/posix_spawn/system, multiprocessing).  `native`: it loads the
project's native code into the interpreter (libln, libln_pull, libln_admin, ln_zenoh_core).
The guard below sees each process start and, in a run without the native tests
(`-m "not native ..."`), each native library load while a test runs, and fails a test that
does what it is not marked for.
"""

from __future__ import annotations

import ctypes
import os
import re
import subprocess
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest
from marking import TESTS, marks_of  # this directory: pytest puts it on sys.path first

if TYPE_CHECKING:
    from netlab import NetLab

REPO = Path(__file__).resolve().parents[2]

for _p in (REPO / "python", REPO, REPO / "tests" / "python"):
    if str(_p) not in sys.path:
        sys.path.insert(0, str(_p))


@pytest.fixture
def netlab(tmp_path: Path) -> Iterator[NetLab]:
    """A NetLab with hosts a (10.77.0.1) and b (10.77.0.2), logs in tmp_path/netlab; add more
    with add_host().  Skips, saying why, where network namespaces cannot be made (fails
    instead under CI=1).  Torn down, with everything in it, after the test."""
    import netlab as netlab_module

    netlab_module.require_netlab()
    with netlab_module.NetLab(tmp_path / "netlab") as lab:
        yield lab


# ---- marking (marking.py) -------------------------------------------------------------------------

def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    for item in items:
        if not isinstance(item, pytest.Function):
            continue
        spawn, native = marks_of(item)
        if spawn:
            item.add_marker(pytest.mark.integration)
        if native:
            item.add_marker(pytest.mark.native)


# ---- the guard: a test that does what it is not marked for fails --------------------------------

FIND_LIBRARY = os.path.join("ctypes", "util.py")
NATIVE_FILES = re.compile(r"lib(ln|ln_pull|ln_admin|ln_zenoh_core)\b[^/]*\.so|ln_admin\.so")


def _left_out(config: pytest.Config, kind: str) -> bool:
    """Whether the run's -m expression leaves out every test marked `kind`."""
    expression = config.getoption("markexpr", "")
    if not expression:
        return False
    from _pytest.mark.expression import Expression

    compiled = Expression.compile(expression)
    others = {"integration", "native"} - {kind}
    return not any(compiled.evaluate(lambda name, marks=marks, **_: name in marks)
                   for marks in ({kind}, {kind} | others))


def _called_from(where: str, outermost: bool = False) -> str | None:
    """The file of the innermost (or outermost) caller, but this file's code, whose path
    starts with `where` (a directory) or ends with it (a file), if any."""
    found = None
    frame = sys._getframe(1)
    while frame is not None:
        name = frame.f_code.co_filename
        if name != __file__ and (name.startswith(where) or name.endswith(where)):
            found = name
            if not outermost:
                break
        frame = frame.f_back
    return found


class _Guard:
    """Notes, while a test runs, each process it starts and each native library it loads."""

    def __init__(self, spawn: bool, native: bool) -> None:
        self.item: pytest.Item | None = None
        self.found: list[str] = []
        self.loaded_at_collection: dict[str, str] = {}  # test file -> library
        if spawn:
            self._wrap_spawn()
        if native:
            self._wrap_load()

    def _note(self, kind: str, what: str) -> None:
        item = self.item
        if item is None:
            return
        if not item.get_closest_marker(kind):
            self.found.append(f"{'starts' if kind == 'integration' else 'loads'} {what}")

    def _wrap_spawn(self) -> None:
        guard = self
        execute_child = subprocess.Popen._execute_child  # type: ignore[attr-defined]

        def checked_execute_child(self: subprocess.Popen[Any], args: Any, *rest: Any,
                                  **kwargs: Any) -> Any:
            # ctypes.util.find_library's ldconfig -p (a library lookup, as by some PyPI
            # packages on import) is not a process the test starts
            if not _called_from(FIND_LIBRARY):
                guard._note("integration", f"a process: {str(args)[:200]}")
            return execute_child(self, args, *rest, **kwargs)

        subprocess.Popen._execute_child = checked_execute_child  # type: ignore[attr-defined]
        for name in ("fork", "forkpty", "posix_spawn", "posix_spawnp", "system"):
            original = getattr(os, name, None)
            if original is not None:
                setattr(os, name, self._checked(original, name))

    def _checked(self, original: Callable[..., Any], name: str) -> Callable[..., Any]:
        def checked(*args: Any, **kwargs: Any) -> Any:
            self._note("integration", f"a process: os.{name}{str(args)[:200]}")
            return original(*args, **kwargs)
        return checked

    def _wrap_load(self) -> None:
        guard = self
        init = ctypes.CDLL.__init__

        def checked_init(self: ctypes.CDLL, name: Any, *args: Any, **kwargs: Any) -> None:
            if name is not None and NATIVE_FILES.search(os.fsdecode(name)):
                if guard.item is None:
                    # the test module (or conftest.py) being imported, not what it imports
                    test_file = _called_from(TESTS, outermost=True)
                    if test_file:
                        guard.loaded_at_collection.setdefault(test_file, str(name))
                guard._note("native", f"native code: {os.fsdecode(name)}")
            init(self, name, *args, **kwargs)

        ctypes.CDLL.__init__ = checked_init  # type: ignore[method-assign]


_GUARD_KEY = pytest.StashKey[_Guard]()


def pytest_configure(config: pytest.Config) -> None:  # the markers: pyproject.toml
    # Starting a process is seen in any run; a native library is loaded once per process, so
    # only a run without the native tests can tell which test loaded it.
    config.stash[_GUARD_KEY] = _Guard(spawn=True, native=_left_out(config, "native"))


@pytest.hookimpl(hookwrapper=True)  # old-style wrappers: Debian 12's pytest 7.2 and pluggy 1.0
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None) -> Iterator[None]:
    guard = item.config.stash.get(_GUARD_KEY, None)
    if guard is None:
        yield
        return
    guard.item, guard.found = item, []
    if not item.get_closest_marker("native"):
        path = Path(str(getattr(item, "path", "")))
        for where, library in guard.loaded_at_collection.items():
            if str(path) == where or (where.endswith(os.sep + "conftest.py")
                                      and path.is_relative_to(Path(where).parent)):
                guard.found.append(f"loads native code when {where} is imported: {library}")
    try:
        yield
    finally:
        guard.item = None


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Iterator[None]:
    outcome = yield
    report = outcome.get_result()
    guard = item.config.stash.get(_GUARD_KEY, None)
    if guard is not None and guard.found and call.when == "teardown":
        report.outcome = "failed"
        report.longrepr = ("not marked, yet it " + "; ".join(dict.fromkeys(guard.found))
                           + "\n(tests/python/conftest.py marks tests by what their code "
                           "reaches; see tests/README.md)")
