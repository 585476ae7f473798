"""How the bindings wait in libln: a wait longer than one slice is made of several libln
waits, because libln goes back to sleep after a signal.  Between them Python runs its
signal handlers (Ctrl-C) and sees a close() from another thread.  A leaf module."""

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
