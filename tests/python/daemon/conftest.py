"""Fixtures of the ln_daemon tests: `daemon`, a private daemon per test (free port, its own
key file and log in the test's tmp_path, a unique instance name), stopped with SIGTERM at
the end; the test fails if the daemon does not exit 0 or leaves any process behind."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from daemonproc import Daemon, start_daemon, stop_daemon


@pytest.fixture
def start(tmp_path: Path) -> Iterator[Callable[..., Daemon]]:
    """start(*extra_args, env=None, key_file=None) -> Daemon; every daemon started is
    stopped and checked."""
    started: list[Daemon] = []

    def run(*args: str, env: dict[str, str] | None = None,
            key_file: Path | None = None) -> Daemon:
        daemon = start_daemon(tmp_path, *args, env=env, key_file=key_file)
        started.append(daemon)
        return daemon

    yield run
    problems = [p for d in started for p in stop_daemon(d)]
    if problems:
        pytest.fail("; ".join(problems))


@pytest.fixture
def daemon(start: Callable[..., Daemon]) -> Daemon:
    return start()
