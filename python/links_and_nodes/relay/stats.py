"""Counters of ln_relay: per link and direction (DirectionStats) and per link (LinkStats),
as the relay updates them and as they appear in the --stats-file JSON."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

UPSTREAM = "upstream"  # from the client (LISTEN side) to the target
DOWNSTREAM = "downstream"  # from the target back to the client
DIRECTIONS = (UPSTREAM, DOWNSTREAM)


@dataclass
class DirectionStats:
    """One direction of one link.  A unit is a datagram (UDP) or a chunk, i.e. one read
    of up to FaultSpec.tcp_chunk bytes (TCP).  `lost` counts loss decisions: for TCP each
    one is a retransmission timeout the chunk waited.  `duplicated` and `reordered` are
    None for TCP, where they do not apply."""

    proto: str
    units_in: int = 0
    units_out: int = 0
    bytes_in: int = 0
    bytes_out: int = 0
    lost: int = 0
    duplicated: int | None = 0
    reordered: int | None = 0
    overflowed: int = 0  # UDP datagrams dropped because the delay queue was full
    errors: int = 0  # UDP: sends the kernel refused, ICMP errors, client sockets not made
    queued: int = 0  # units waiting in the delay queue right now
    queued_bytes: int = 0

    def __post_init__(self) -> None:
        if self.proto == "tcp":
            self.duplicated = None
            self.reordered = None

    def sent(self, size: int) -> None:
        self.units_out += 1
        self.bytes_out += size

    def as_dict(self) -> dict[str, Any]:
        unit = "datagrams" if self.proto == "udp" else "chunks"
        return {f"{unit}_in": self.units_in, f"{unit}_out": self.units_out,
                "bytes_in": self.bytes_in, "bytes_out": self.bytes_out, "lost": self.lost,
                "duplicated": self.duplicated, "reordered": self.reordered,
                "overflowed": self.overflowed, "errors": self.errors, "queued": self.queued,
                "queued_bytes": self.queued_bytes}

    def summary(self) -> str:
        unit = "datagrams" if self.proto == "udp" else "chunks"
        text = (f"{self.units_in} {unit} in, {self.units_out} out, {self.lost} lost")
        if self.proto == "udp":
            text += (f", {self.duplicated} duplicated, {self.reordered} reordered, "
                     f"{self.overflowed} overflowed")
        text += f", {self.bytes_in} bytes in, {self.bytes_out} out"
        if self.errors:
            text += f", {self.errors} errors"
        if self.queued:
            text += f", {self.queued} still queued"
        return text


@dataclass
class LinkStats:
    """One link: its endpoints (`listen` as bound, once the relay started), both
    directions and its peers (UDP clients or TCP connections)."""

    proto: str
    listen: str
    target: str
    upstream: DirectionStats = field(init=False)
    downstream: DirectionStats = field(init=False)
    peers: int = 0  # UDP clients seen / TCP connections accepted
    active: int = 0  # UDP clients with an upstream socket / TCP connections open
    connect_failed: int = 0  # TCP connections to the target that failed
    aborted: int = 0  # TCP connections reset after tcp_retries losses of one chunk
    resets: int = 0  # TCP connections reset because a side reset or a write failed

    def __post_init__(self) -> None:
        self.upstream = DirectionStats(self.proto)
        self.downstream = DirectionStats(self.proto)

    def as_dict(self) -> dict[str, Any]:
        result: dict[str, Any] = {"proto": self.proto, "listen": self.listen,
                                  "target": self.target}
        if self.proto == "udp":
            result.update(clients=self.peers, active_clients=self.active)
        else:
            result.update(connections=self.peers, active_connections=self.active,
                          connect_failed=self.connect_failed, aborted=self.aborted,
                          resets=self.resets)
        result.update(upstream=self.upstream.as_dict(), downstream=self.downstream.as_dict())
        return result
