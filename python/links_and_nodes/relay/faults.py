"""The faults ln_relay injects (FaultSpec): loss, delay and jitter, duplication,
reordering, the TCP retransmission timeout model and the memory bound of a delay queue.
Validated on construction, so the library and the command line reject the same values."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from typing import Any

MIB = 1 << 20


@dataclass(frozen=True)
class FaultSpec:
    """What happens to traffic in each direction of a link (docs/relay.md).

    Probabilities are in 0..1 and times in milliseconds; `delay_ms ± jitter_ms` is one-way,
    per direction.  `duplicate` and `reorder` apply to UDP only.  `one_way` limits the
    faults to the direction from the client to the target; the replies pass unharmed."""

    loss: float = 0.0
    delay_ms: float = 0.0
    jitter_ms: float = 0.0
    duplicate: float = 0.0
    reorder: float = 0.0
    reorder_flush_ms: float = 50.0  # a held datagram with no follower goes after this
    rto_ms: float = 200.0  # TCP: first retransmission timeout of a lost chunk
    rto_max_ms: float = 3000.0  # TCP: the doubling stops here
    tcp_retries: int = 15  # TCP: lost retransmissions of one chunk before a reset
    tcp_chunk: int = 65536  # TCP: most bytes read (and faulted) at a time
    queue_limit: int = 64 * MIB  # bytes waiting in one direction's delay queue
    one_way: bool = False

    def __post_init__(self) -> None:
        for name in ("loss", "duplicate", "reorder"):
            value = getattr(self, name)
            if not (_is_number(value) and 0.0 <= value <= 1.0):
                raise ValueError(f"{name} must be a probability in 0..1, not {value!r}")
        for name in ("delay_ms", "jitter_ms", "reorder_flush_ms", "rto_ms", "rto_max_ms"):
            value = getattr(self, name)
            if not (_is_number(value) and math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a finite number of milliseconds >= 0, "
                                 f"not {value!r}")
        if self.rto_ms <= 0:
            raise ValueError(f"rto_ms must be > 0, not {self.rto_ms!r}")
        if self.rto_max_ms < self.rto_ms:
            raise ValueError(f"rto_max_ms ({self.rto_max_ms!r}) must be at least rto_ms "
                             f"({self.rto_ms!r})")
        for name, low in (("tcp_retries", 0), ("tcp_chunk", 1), ("queue_limit", 1)):
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool) or value < low:
                raise ValueError(f"{name} must be an integer >= {low}, not {value!r}")

    @property
    def harmless(self) -> bool:
        """True when nothing is lost, delayed, duplicated or reordered."""
        return not (self.loss or self.delay_ms or self.jitter_ms or self.duplicate
                    or self.reorder)

    def for_direction(self, upstream: bool) -> FaultSpec:
        """The faults of one direction: with one_way, none (but the same limits) on the
        way back from the target."""
        if upstream or not self.one_way:
            return self
        return replace(self, loss=0.0, delay_ms=0.0, jitter_ms=0.0, duplicate=0.0,
                       reorder=0.0)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


NO_FAULTS = FaultSpec()
