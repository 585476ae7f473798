"""The progress line of ln_bag on stderr: only when stderr is a terminal (and not -q),
redrawn at most 5 times a second, erased at the end."""

from __future__ import annotations

import sys
import time


class Progress:
    """Samples done out of `total` (None: unknown) and the MB of them."""

    def __init__(self, label: str, total: int | None = None, enabled: bool | None = None
                 ) -> None:
        self.label = label
        self.total = total
        self.enabled = sys.stderr.isatty() if enabled is None else enabled
        self.samples = 0
        self.bytes = 0
        self._next = 0.0
        self._started = time.monotonic()

    def add(self, nbytes: int) -> None:
        self.samples += 1
        self.bytes += nbytes
        if self.enabled and not self.samples & 1023:
            now = time.monotonic()
            if now >= self._next:
                self._next = now + 0.2
                self._draw(now)

    def add_block(self, samples: int, nbytes: int) -> None:
        """`samples` done at once (a chunk), `nbytes` of them."""
        before = self.samples
        self.samples += samples
        self.bytes += nbytes
        if self.enabled and (self.samples >> 10) != (before >> 10):
            now = time.monotonic()
            if now >= self._next:
                self._next = now + 0.2
                self._draw(now)

    def _draw(self, now: float) -> None:
        share = f" ({100 * self.samples / self.total:.0f} %)" if self.total else ""
        rate = self.bytes / 1e6 / max(now - self._started, 1e-9)
        sys.stderr.write(f"\r\033[K{self.label}: {self.samples} samples{share}, "
                         f"{self.bytes / 1e6:.1f} MB ({rate:.1f} MB/s)")
        sys.stderr.flush()

    def done(self) -> None:
        if self.enabled:
            sys.stderr.write("\r\033[K")
            sys.stderr.flush()
