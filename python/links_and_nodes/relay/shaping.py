"""The fault decisions of one direction of a link, without sockets or an event loop: the
caller passes the time, so the same seed and the same input give the same output and the
rules can be tested with made-up clocks.  DatagramShaper is UDP's (loss, duplication,
delay ± jitter, reordering, a bounded queue); StreamShaper is TCP's (delay ± jitter in
order, loss as a retransmission timeout with head-of-line blocking)."""

from __future__ import annotations

import heapq
import itertools
import random
from dataclasses import dataclass, field
from typing import Generic, TypeVar

from .faults import FaultSpec
from .stats import DirectionStats

T = TypeVar("T")

# Random numbers drawn for each datagram, whatever the outcome, so that one decision never
# shifts the others: with the same seed, the datagrams lost at loss 0.1 are also lost at 0.2.
DRAWS_PER_DATAGRAM = 5


def delay_s(faults: FaultSpec, u: float) -> float:
    """delay ± jitter in seconds for a uniform number u in [0, 1); never negative."""
    return max(0.0, faults.delay_ms + faults.jitter_ms * (2.0 * u - 1.0)) / 1000.0


@dataclass
class _Held(Generic[T]):
    """A datagram (both copies, if duplicated) kept back for the next one to overtake."""

    deadline: float  # released by itself at this time if no follower came
    copies: list[tuple[float, T, int]] = field(default_factory=list)  # (due, item, size)


class DatagramShaper(Generic[T]):
    """One direction of a UDP link.  `push` decides what happens to a datagram (an opaque
    item of `size` bytes); `pop_due` returns, in sending order, what is due by `now`;
    `next_wakeup` says when to call it again.  The caller counts what it managed to send
    (DirectionStats.sent).

    Per datagram: lost with probability `loss`; else duplicated with probability
    `duplicate` (each copy has its own delay); each copy waits delay ± jitter; with
    probability `reorder` it is held back until the next datagram that is not lost has
    been queued, and then goes right behind that one (or on its own after
    `reorder_flush_ms` if none comes).  One datagram is held at a time: a datagram drawn
    for reordering while another is held is that one's follower instead.  Datagrams that
    would take the queued bytes over `queue_limit` are dropped (`overflowed`)."""

    def __init__(self, faults: FaultSpec, rng: random.Random, stats: DirectionStats) -> None:
        self.faults = faults
        self._rng = rng
        self.stats = stats
        self._heap: list[tuple[float, int, T, int]] = []
        self._order = itertools.count()  # ties on the due time go out in queueing order
        self._held: _Held[T] | None = None

    def push(self, item: T, size: int, now: float) -> None:
        stats, faults = self.stats, self.faults
        stats.units_in += 1
        stats.bytes_in += size
        if faults.harmless:
            self._queue(now, item, size)
            return
        u_loss, u_dup, u_reorder, u_delay, u_dup_delay = (
            self._rng.random() for _ in range(DRAWS_PER_DATAGRAM))
        if u_loss < faults.loss:
            stats.lost += 1
            return
        dues = [now + delay_s(faults, u_delay)]
        if u_dup < faults.duplicate:
            stats.duplicated = (stats.duplicated or 0) + 1
            dues.append(now + delay_s(faults, u_dup_delay))
        held, self._held = self._held, None
        if held is None and u_reorder < faults.reorder:
            hold = _Held[T](now + faults.reorder_flush_ms / 1000.0)
            for due in dues:
                if self._admit(size):
                    hold.copies.append((due, item, size))
            if hold.copies:
                self._held = hold
            return
        last = max(self._queue(due, item, size) for due in dues)
        if held is not None:
            # The follower is queued: the held datagram goes right behind it.
            stats.reordered = (stats.reordered or 0) + 1
            self._release(held, last)

    def next_wakeup(self) -> float | None:
        """When something is next due (or a held datagram's wait ends); None if idle."""
        times = []
        if self._heap:
            times.append(self._heap[0][0])
        if self._held is not None:
            times.append(self._held.deadline)
        return min(times) if times else None

    def pop_due(self, now: float) -> list[tuple[T, int]]:
        """What is due by `now`, in sending order, as (item, size)."""
        if self._held is not None and self._held.deadline <= now:
            held, self._held = self._held, None
            self._release(held, now)
        out: list[tuple[T, int]] = []
        stats = self.stats
        while self._heap and self._heap[0][0] <= now:
            _, _, item, size = heapq.heappop(self._heap)
            stats.queued -= 1
            stats.queued_bytes -= size
            out.append((item, size))
        return out

    def clear(self) -> None:
        """Forget everything queued (the relay is closing); `queued` keeps its count."""
        self._heap.clear()
        self._held = None

    def _admit(self, size: int) -> bool:
        stats = self.stats
        if stats.queued_bytes + size > self.faults.queue_limit:
            stats.overflowed += 1
            return False
        stats.queued += 1
        stats.queued_bytes += size
        return True

    def _queue(self, due: float, item: T, size: int) -> float:
        if self._admit(size):
            heapq.heappush(self._heap, (due, next(self._order), item, size))
        return due

    def _release(self, held: _Held[T], after: float) -> None:
        # Already admitted (counted in queued) when it was held.
        for due, item, size in held.copies:
            heapq.heappush(self._heap, (max(due, after), next(self._order), item, size))


class StreamShaper:
    """One direction of one TCP connection.  `admit` gives the time a chunk read at `now`
    is to be written on: never before the chunk ahead of it (the byte stream keeps its
    order), delay ± jitter after it was read, plus, for each time it is drawn as lost, a
    retransmission timeout (rto_ms, doubling up to rto_max_ms) during which it and
    everything behind it wait, as the receiving application of a lossy TCP path sees it.
    After tcp_retries lost retransmissions of one chunk the connection is to be reset,
    once the timeouts have passed, as TCP gives up."""

    def __init__(self, faults: FaultSpec, rng: random.Random, stats: DirectionStats) -> None:
        self.faults = faults
        self._rng = rng
        self.stats = stats
        self._last_due = float("-inf")

    def admit(self, size: int, now: float) -> tuple[float, bool]:
        """(due time, whether the connection is to be reset then instead) of a chunk."""
        faults, stats = self.faults, self.stats
        stats.units_in += 1
        stats.bytes_in += size
        if faults.harmless:
            return self._after(now), False
        waited = 0.0
        rto = faults.rto_ms / 1000.0
        losses = 0
        while self._rng.random() < faults.loss:
            stats.lost += 1
            losses += 1
            waited += rto
            rto = min(2.0 * rto, faults.rto_max_ms / 1000.0)
            if losses > faults.tcp_retries:
                return self._after(now + waited), True
        return self._after(now + waited + delay_s(faults, self._rng.random())), False

    def eof_due(self, now: float) -> float:
        """When the end of the stream (FIN) is to be passed on: behind the last chunk."""
        if self.faults.harmless:
            return self._after(now)
        return self._after(now + delay_s(self.faults, self._rng.random()))

    def _after(self, due: float) -> float:
        self._last_due = max(self._last_due, due)
        return self._last_due
