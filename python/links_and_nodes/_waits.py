"""How the bindings wait in libln.  Reads and waitsets wait once for the whole time: libln
returns LN_EINTR after a signal, run_signal_handlers() lets Python run its handlers
(Ctrl-C) and the caller waits for the rest.  Writes, loans and service-group waits, where
libln goes back to sleep after a signal, are made of slices: between them Python runs its
handlers and sees a close() from another thread.  A leaf module."""

from __future__ import annotations

import math
import time

# Longest single wait inside libln (seconds).
SLICE = 0.1


def first_slice(timeout: float | None) -> float:
    """The timeout of the first libln wait of `timeout` (None: forever): all of it if it
    fits in a slice, else one slice.  NaN goes through, for libln to refuse."""
    if timeout is None:
        return SLICE
    t = float(timeout)
    return SLICE if t < 0 or t > SLICE else t


def waits_longer(timeout: float | None) -> bool:
    """Whether a wait of `timeout` needs more than one slice."""
    return timeout is None or timeout < 0 or timeout > SLICE


def deadline(timeout: float | None) -> float:
    """The monotonic time at which a wait of `timeout` ends, once its first slice has
    passed; infinite for None, negative or over 1e9 s (forever, as libln counts it)."""
    if timeout is None or timeout < 0 or timeout > 1e9:
        return math.inf
    return time.monotonic() + timeout - SLICE


def next_slice(end: float) -> float:
    """The timeout of the next libln wait before `end`; <= 0 once it has passed."""
    return SLICE if end == math.inf else min(SLICE, end - time.monotonic())


def run_signal_handlers() -> None:
    """Called after libln returned LN_EINTR: entering a Python function is where the
    interpreter runs the handlers of signals that came meanwhile (KeyboardInterrupt for
    Ctrl-C is raised from here); other threads than the main one only pass through."""


def end_of(timeout: float | None, start: float) -> float:
    """The monotonic time at which a wait of `timeout` that began at `start` ends: infinite
    for None, negative or over 1e9 s (forever, as libln counts it).  (libln refuses NaN
    before it waits.)"""
    if timeout is None or not 0 <= timeout <= 1e9:
        return math.inf
    return start + timeout


def remaining(end: float) -> float:
    """The timeout of the next libln wait before `end` (-1: forever; 0 once it passed)."""
    return -1.0 if end == math.inf else max(0.0, end - time.monotonic())
