"""Fixtures of the ln_manager tests: a unique instance name per test (so tests run in
parallel), a private runtime directory, and `start_manager`, which runs the manager as a
subprocess with --port 0 and waits for its ready line.  Every manager and every segment of
the test's instances is gone after the test, whatever happened."""

from __future__ import annotations

import signal
import subprocess
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from mgrproc import SHM, WAIT, Manager, segments, unique_instance


@pytest.fixture
def instance() -> str:
    return unique_instance()


@pytest.fixture
def start_manager(tmp_path: Path) -> Iterator[Callable[..., Manager]]:
    """start_manager(instance, *args, runtime=None, ready=True) -> Manager."""
    started: list[Manager] = []

    def start(instance: str, *args: str, runtime: Path | None = None,
              ready: bool = True) -> Manager:
        runtime = runtime or tmp_path / f"run-{instance}"
        manager = Manager(instance, runtime, tmp_path / f"manager-{len(started)}.log",
                          list(args))
        started.append(manager)
        return manager.wait_ready() if ready else manager

    yield start
    # A manager still running now is stopped as in production, with SIGTERM: it must exit
    # 0 and leave no segment behind.  Segments of killed managers are simply removed.
    problems = []
    unchecked = {m.instance for m in started if m.proc.poll() is not None}
    for manager in started:
        if manager.proc.poll() is None:
            manager.proc.send_signal(signal.SIGTERM)
            try:
                if manager.proc.wait(WAIT) != 0:
                    problems.append(f"ln_manager {manager.instance} exited with "
                                    f"{manager.proc.returncode}")
            except subprocess.TimeoutExpired:
                manager.kill()
                problems.append(f"ln_manager {manager.instance} ignored SIGTERM")
        if manager.proc.stdout is not None:
            manager.proc.stdout.close()
    for instance in {m.instance for m in started}:
        left = segments(instance)
        for name in left:
            (SHM / name).unlink(missing_ok=True)
        if left and instance not in unchecked:
            problems.append(f"segments left after SIGTERM: {left}")
    if problems:
        pytest.fail("; ".join(problems))


@pytest.fixture
def manager(start_manager: Callable[..., Manager], instance: str) -> Manager:
    return start_manager(instance)
