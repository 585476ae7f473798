"""Helpers the end-to-end tests share: waiting for a condition with an upper bound (which is
never a measurement, only how long a test may hang before it fails), a free TCP port, a
free port for an ln_daemon (with its data port beside it), the live processes whose
command line holds a marker, and Ctrl-C as in a terminal for a child process."""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import time
from collections.abc import Callable
from pathlib import Path

import pytest

WAIT = 60.0  # seconds; only ever an upper bound while waiting for something to happen


def wait_for(predicate: Callable[[], object], what: str, timeout: float = WAIT) -> object:
    """Poll until `predicate()` is true and return its value; fail the test naming `what`
    after `timeout`."""
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            pytest.fail(f"gave up waiting for {what}")
        time.sleep(0.02)


def free_port() -> int:
    """A TCP port nothing listens on right now (the kernel's pick)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def free_daemon_port() -> int:
    """A port P for an ln_daemon that takes its default data port P + 1: P is free for TCP
    and P + 1 for TCP and UDP on every interface right now.  (The kernel hands out ports
    of the form P + 1 as source ports of outgoing connections, which then hold them for a
    while: a plain free_port() for a daemon would now and then find its data port taken.)"""
    for _ in range(100):
        port = free_port()
        try:
            with contextlib.ExitStack() as stack:
                for kind in (socket.SOCK_STREAM, socket.SOCK_DGRAM):
                    s = stack.enter_context(socket.socket(socket.AF_INET, kind))
                    s.bind(("0.0.0.0", port + 1))
            return port
        except OSError:
            continue
    pytest.fail("found no free port with a free neighbour for an ln_daemon")


def pids_with(marker: str | bytes) -> list[int]:
    """Pids of live (not zombie) processes whose command line contains `marker`."""
    needle = marker.encode() if isinstance(marker, str) else marker
    found = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            raw = Path(f"/proc/{entry}/cmdline").read_bytes()
            stat = Path(f"/proc/{entry}/stat").read_text()
        except OSError:
            continue
        if needle in raw and stat.rsplit(")", 1)[1].split()[0] != "Z":
            found.append(int(entry))
    return found


def sigint_default() -> None:
    """A child's preexec_fn: Ctrl-C as in a terminal, also under a runner that ignores SIGINT
    (a background job), whose children would inherit that."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
