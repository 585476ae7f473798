"""Rates of a topic for `topic hz` and `topic bw` (docs/introspection.md), from the sequence
numbers and publish timestamps of the samples a subscriber saw: a window of the newest
samples, the periods between consecutive ones, and their statistics.  Pure: the timestamps
are the publishers' (CLOCK_REALTIME at publish), never the time they were read."""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from itertools import pairwise
from typing import Any

DEFAULT_WINDOW = 10000  # samples, as ros2 topic hz


@dataclass(frozen=True)
class PeriodStats:
    """Statistics of a window of samples.

    `periods` are the intervals between samples with consecutive sequence numbers (a gap,
    samples this subscriber did not see, is no period); `missed` how many sequence numbers
    between the window's first and last sample it does not hold.  `rate_hz` is the topic's
    rate over the window: sequence numbers per second between its first and last sample,
    so missed samples count.  Durations are in seconds; None without periods."""

    samples: int
    periods: int
    missed: int
    span_s: float
    rate_hz: float
    mean_s: float | None
    min_s: float | None
    max_s: float | None
    std_s: float | None

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def period_stats(samples: Sequence[tuple[int, int]]) -> PeriodStats | None:
    """The statistics of `samples`, (sequence number, publish time in ns) in increasing
    sequence order; None for fewer than two.  The standard deviation is that of the
    population of periods."""
    if len(samples) < 2:
        return None
    periods = [(t1 - t0) / 1e9 for (s0, t0), (s1, t1) in pairwise(samples) if s1 - s0 == 1]
    first_seq, first_t = samples[0]
    last_seq, last_t = samples[-1]
    span = (last_t - first_t) / 1e9
    rate = (last_seq - first_seq) / span if span > 0 else 0.0
    missed = (last_seq - first_seq + 1) - len(samples)
    if not periods:
        return PeriodStats(len(samples), 0, missed, span, rate, None, None, None, None)
    mean = math.fsum(periods) / len(periods)
    std = math.sqrt(math.fsum((p - mean) ** 2 for p in periods) / len(periods))
    return PeriodStats(len(samples), len(periods), missed, span, rate, mean, min(periods),
                       max(periods), std)


def bandwidth(stats: PeriodStats, message_size: int) -> float:
    """Bytes per second: every sample of a topic has the message size."""
    return stats.rate_hz * message_size


class Window:
    """The newest `size` samples of one subscription.  A sequence number that does not go
    up (the topic was made anew, counting from 1 again) starts the window over."""

    def __init__(self, size: int = DEFAULT_WINDOW) -> None:
        if size < 2:
            raise ValueError(f"a window needs at least 2 samples, not {size}")
        self.samples: deque[tuple[int, int]] = deque(maxlen=size)
        self.received = 0  # every sample added, also those that left the window

    def add(self, seq: int, timestamp_ns: int) -> None:
        if self.samples and seq <= self.samples[-1][0]:
            self.samples.clear()
        self.samples.append((seq, timestamp_ns))
        self.received += 1

    def stats(self) -> PeriodStats | None:
        return period_stats(self.samples)


def duration(seconds: float | None) -> str:
    """`1.000 ms`, `250.0 us`, `2.500 s`."""
    if seconds is None:
        return "-"
    size = abs(seconds)
    if size >= 1:
        return f"{seconds:.3f} s"
    if size >= 1e-3:
        return f"{seconds * 1e3:.3f} ms"
    return f"{seconds * 1e6:.1f} us"


def byte_rate(value: float) -> str:
    """`512 B/s`, `18.00 KB/s`, `1.50 MB/s` (powers of 1000, as the console's tables)."""
    for unit in ("B", "KB", "MB", "GB"):
        if abs(value) < 1000 or unit == "GB":
            return f"{value:.0f} {unit}/s" if unit == "B" else f"{value:.2f} {unit}/s"
        value /= 1000
    raise AssertionError("unreachable")


def _counts(stats: PeriodStats) -> str:
    return f"{stats.samples} samples, {stats.periods} periods, {stats.missed} missed"


def hz_line(stats: PeriodStats) -> str:
    """What `topic hz` prints of a window."""
    return (f"rate: {stats.rate_hz:.3f} Hz  mean: {duration(stats.mean_s)}  "
            f"min: {duration(stats.min_s)}  max: {duration(stats.max_s)}  "
            f"std dev: {duration(stats.std_s)}  window: {_counts(stats)}")


def bw_line(stats: PeriodStats, message_size: int) -> str:
    """What `topic bw` prints of a window."""
    return (f"bandwidth: {byte_rate(bandwidth(stats, message_size))}  "
            f"({message_size} B x {stats.rate_hz:.3f} Hz)  window: {_counts(stats)}")
