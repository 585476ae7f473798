"""Relay: a set of UDP and TCP links sharing one FaultSpec and one seed, for asyncio code
and tests: start, the bound addresses, live stats and a JSON report, close.  Link i's
directions draw from random.Random(f"{seed}/{i}/...") so that a run can be repeated."""

from __future__ import annotations

import secrets
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

from .addresses import Address, RelayError, format_address, parse_address
from .faults import NO_FAULTS, FaultSpec
from .stats import LinkStats
from .tcp import TcpLink
from .udp import UdpLink

Proto = Literal["udp", "tcp"]


def _address(value: str | Address, *, listen: bool) -> Address:
    if isinstance(value, str):
        return parse_address(value, allow_port_zero=listen)
    host, port = value
    return parse_address(format_address((host, port)), allow_port_zero=listen)


@dataclass(frozen=True)
class Link:
    """Relay `proto` traffic arriving at `listen` to `target`.  Addresses are
    (host, port) or `HOST:PORT` / `[V6HOST]:PORT` text; port 0 in `listen` lets the
    kernel pick one (Relay.bound tells which)."""

    proto: Proto
    listen: Address
    target: Address

    def __init__(self, proto: Proto, listen: str | Address, target: str | Address) -> None:
        if proto not in ("udp", "tcp"):
            raise ValueError(f"proto must be 'udp' or 'tcp', not {proto!r}")
        object.__setattr__(self, "proto", proto)
        object.__setattr__(self, "listen", _address(listen, listen=True))
        object.__setattr__(self, "target", _address(target, listen=False))

    @classmethod
    def udp(cls, listen: str | Address, target: str | Address) -> Link:
        return cls("udp", listen, target)

    @classmethod
    def tcp(cls, listen: str | Address, target: str | Address) -> Link:
        return cls("tcp", listen, target)

    def __str__(self) -> str:
        return f"{self.proto} {format_address(self.listen)} -> {format_address(self.target)}"


class Relay:
    """The links of one relay.

        async with Relay([Link.udp("127.0.0.1:0", "127.0.0.1:6000")],
                         FaultSpec(loss=0.1, delay_ms=5), seed=1) as relay:
            port = relay.bound[0][1]
            ...
            print(relay.stats[0].upstream.lost)

    Without a seed one is picked at random; `seed` says which, so the run can be repeated.
    `udp_idle_s` is how long a UDP client's socket to the target outlives its traffic."""

    def __init__(self, links: Sequence[Link], faults: FaultSpec = NO_FAULTS,
                 seed: int | None = None, *, udp_idle_s: float = 120.0) -> None:
        if not links:
            raise ValueError("a relay needs at least one link")
        if not udp_idle_s > 0:
            raise ValueError(f"udp_idle_s must be > 0, not {udp_idle_s!r}")
        self.links = tuple(links)
        self.faults = faults
        self.seed = secrets.randbits(32) if seed is None else seed
        self.stats = tuple(LinkStats(link.proto, format_address(link.listen),
                                     format_address(link.target)) for link in self.links)
        self._udp_idle_s = udp_idle_s
        self._running: list[UdpLink | TcpLink] = []

    async def start(self) -> None:
        """Bind every link; RelayError naming the link if one cannot start (the others
        are closed again)."""
        if self._running:
            raise RuntimeError("the relay is running already")
        try:
            for index, (link, stats) in enumerate(zip(self.links, self.stats, strict=True)):
                seed = f"{self.seed}/{index}/{link.proto}"
                running: UdpLink | TcpLink
                if link.proto == "udp":
                    running = UdpLink(link.listen, link.target, self.faults, seed, stats,
                                      idle_s=self._udp_idle_s)
                else:
                    running = TcpLink(link.listen, link.target, self.faults, seed, stats)
                try:
                    await running.start()
                except RelayError as exc:
                    raise RelayError(f"{link}: {exc}") from None
                except OSError as exc:
                    raise RelayError(f"{link}: cannot listen on "
                                     f"{format_address(link.listen)}: "
                                     f"{exc.strerror or exc}") from None
                if running.bound is not None:
                    stats.listen = format_address(running.bound)
                self._running.append(running)
        except BaseException:
            await self.close()
            raise

    @property
    def bound(self) -> list[Address]:
        """The (host, port) each link listens on, in the order of the links."""
        if len(self._running) != len(self.links):
            raise RuntimeError("the relay is not running")
        return [running.bound for running in self._running if running.bound is not None]

    def report(self) -> dict[str, Any]:
        """Seed, faults and every link's stats, as --stats-file has them."""
        return {"seed": self.seed, "faults": self.faults.as_dict(),
                "links": [stats.as_dict() for stats in self.stats]}

    async def close(self) -> None:
        """Stop listening, reset open TCP connections, drop what is still queued (the
        stats keep counting it as queued)."""
        running, self._running = self._running, []
        for link in running:
            await link.close()

    async def __aenter__(self) -> Relay:
        await self.start()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()
