"""Rates for the graph (docs/introspection.md, "graph"): counters that only grow (a topic's
published samples, its ring's write_seq; a service's calls) looked at now and then, each
rate taken between the newest look and an earlier one at least MIN_SPAN seconds before it.
Pure: the caller passes the time and the counters.  Leaf module."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

MIN_SPAN = 0.5  # seconds: a shorter span between two looks gives no rate
MAX_AGE = 10.0  # seconds: older looks are forgotten (a rate over them would be stale)
KEPT = 32  # looks kept at most


@dataclass(frozen=True)
class Look:
    time: float  # monotonic seconds
    counters: dict[str, int]


class Rates:
    """The looks at a set of counters; `rates()` per counter, per second."""

    def __init__(self) -> None:
        self._looks: deque[Look] = deque(maxlen=KEPT)

    def base(self, now: float) -> Look | None:
        """The newest look at least MIN_SPAN old and at most MAX_AGE old."""
        for look in reversed(self._looks):
            age = now - look.time
            if age > MAX_AGE:
                return None
            if age >= MIN_SPAN:
                return look
        return None

    def add(self, now: float, counters: dict[str, int]) -> tuple[dict[str, float], float | None]:
        """Keep a look; the rate of every counter against the base look (a counter that is
        new or went down has none) and the span in seconds (None: no base look yet)."""
        base = self.base(now)
        if not self._looks or now - self._looks[-1].time >= MIN_SPAN / 2:
            self._looks.append(Look(now, dict(counters)))
        if base is None:
            return {}, None
        span = now - base.time
        rates = {key: (value - base.counters[key]) / span for key, value in counters.items()
                 if key in base.counters and value >= base.counters[key]}
        return rates, span
