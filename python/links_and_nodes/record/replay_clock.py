"""The replay clock of `ln_play --clock`: topic `ln.clock` (md ln/clock) with the replay
time, its rate and whether it is paused, published periodically and on every change of the
timeline; clients follow it with use_clock() / now() (docs/recording.md)."""

from __future__ import annotations

import time
from typing import Any

CLOCK_TOPIC = "ln.clock"
CLOCK_MD = "ln/clock"


class ReplayClock:
    """Publishes a Playback's timeline on `topic` every 1/hz seconds (tick()) and at once
    on every change (publish())."""

    def __init__(self, client: Any, topic: str = CLOCK_TOPIC, hz: float = 100.0) -> None:
        self.port = client.publish(topic, CLOCK_MD)
        self.period = 1.0 / hz
        self._due = 0.0

    def publish(self, playback: Any) -> None:
        mono, real = time.monotonic(), time.time_ns()
        msg = self.port.packet
        msg.time_ns = playback.position(mono)
        msg.stamp_ns = real
        msg.rate = playback.rate
        msg.epoch = playback.epoch & 0xFFFFFFFF
        msg.paused = int(playback.state != "playing")
        self.port.write()
        self._due = mono + self.period

    def tick(self, playback: Any) -> float:
        """Publish if a period has passed; the seconds until the next one is due."""
        now = time.monotonic()
        if now >= self._due:
            self.publish(playback)
            now = time.monotonic()
        return max(0.0, self._due - now)
