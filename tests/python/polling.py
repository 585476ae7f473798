"""Helpers the end-to-end tests share: waiting for a condition with an upper bound (which is
never a measurement, only how long a test may hang before it fails) and a free TCP port."""

from __future__ import annotations

import socket
import time
from collections.abc import Callable

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
