"""The daemon link of every host of the configuration: connecting and reconnecting,
pinging, learning each host's id and data port, marking a host unreachable with the
reason, and letting a client's port request wait until its host is known."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from dataclasses import dataclass, field
from typing import Any, Protocol

from ..config import model
from ..processes import daemon_wire as dw
from ..processes.daemons import DaemonPool
from ..registry.core import Core
from ..registry.rings import RemoteRings
from . import limits, routes

log = logging.getLogger("ln_manager")


@dataclass(eq=False)
class HostState:
    """One host of the configuration and its daemon link."""

    name: str
    node: str  # what DaemonPool.link takes for it
    state: str = "connecting"  # connecting | up | unreachable
    error: str = ""
    host_id: str = ""
    data_port: int = 0
    since: float = field(default_factory=time.monotonic)
    client: Any = None  # dc.DaemonClient while up
    local: bool = False  # the manager's own host (its rings are core.local)
    rings: RemoteRings | None = None
    purged: bool = False  # stale segments of an earlier manager removed (once)
    published: dict[int, int] = field(default_factory=dict)  # topic id -> last write seq

    def info(self) -> dict[str, Any]:
        return {"name": self.name, "state": self.state, "error": self.error,
                "host_id": self.host_id, "data_port": self.data_port, "local": self.local,
                "for_s": round(time.monotonic() - self.since, 1)}


def config_hosts(config: model.Config, prefix: str) -> dict[str, HostState]:
    """A HostState, with its rings, for every host of the configuration."""
    hosts: dict[str, HostState] = {}
    for index, (name, node) in enumerate(routes.config_hosts(config), start=1):
        host = HostState(name, node)
        host.rings = RemoteRings(name, prefix, f"h{index}")
        hosts[name] = host
    return hosts


class HostStreams(Protocol):
    """What the monitor tells the streams of a host (streams.Forwarding)."""

    def tokens(self) -> set[int]: ...
    def host_up(self, name: str) -> None: ...
    def host_down(self, name: str, reason: str) -> None: ...
    def take_stats(self, host: HostState, stats: list[Any], totals: Any) -> None: ...


class HostMonitor:
    """Keeps `hosts` up to date: one monitoring loop per host."""

    def __init__(self, hosts: dict[str, HostState], config: model.Config, core: Core,
                 pool: DaemonPool, local_id: str, streams: HostStreams) -> None:
        self.hosts = hosts
        self.config = config
        self.core = core
        self.pool = pool
        self.local_id = local_id
        self.streams = streams
        self._identified = asyncio.Event()  # set (and replaced) whenever a host comes up
        self.closing = False

    def known(self, host_id: str) -> bool:
        return (not host_id or host_id == self.local_id
                or any(h.host_id == host_id for h in self.hosts.values()))

    async def identify(self, host_id: str) -> None:
        """Until a host with this id is up (boundedly; not at all once every host is)."""
        loop = asyncio.get_running_loop()
        deadline = loop.time() + limits.IDENTIFY_TIMEOUT
        while not self.known(host_id):
            left = deadline - loop.time()
            if left <= 0 or all(h.state == "up" for h in self.hosts.values()):
                return  # rings_for tells the client why its host is unknown
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._identified.wait(),
                                       min(left, limits.POLL_INTERVAL))

    async def run(self, host: HostState) -> None:
        """Monitor one host until closing."""
        while not self.closing:
            try:
                await self.check(host)
            except asyncio.CancelledError:
                raise
            except Exception as exc:  # DaemonError, OSError, TimeoutError, ...
                await self.down(host, limits.reason(exc))
            await asyncio.sleep(limits.POLL_INTERVAL)

    async def check(self, host: HostState) -> None:
        """One round: (re)connect, ping, poll the stream counters; raises if that fails."""
        client = await asyncio.wait_for(self.pool.link(host.node), limits.CONNECT_TIMEOUT)
        if client is not host.client:
            await self._up(host, client)
        await asyncio.wait_for(client.ping(), limits.PING_TIMEOUT)
        stats, totals = await asyncio.wait_for(client.stream_stats(), limits.PING_TIMEOUT)
        self.streams.take_stats(host, stats, totals)

    async def _up(self, host: HostState, client: Any) -> None:
        info = await asyncio.wait_for(client.net_info(), limits.PING_TIMEOUT)
        configured = self.config.hosts.get(host.name)
        local = info.host_id == self.local_id
        if not local and host.rings is not None:
            # No ring of the host changes meanwhile; every call is bounded, since client
            # requests wait for the lock and this monitor is what gives up on a daemon.
            async with self.core.transit():
                if not host.purged:
                    # segments and streams an earlier manager of this instance left there
                    removed = await asyncio.wait_for(client.ring_purge(), limits.PING_TIMEOUT)
                    host.purged = True
                    if removed:
                        log.info("host %r: removed %d stale segment%s of this instance",
                                 host.name, removed, "" if removed == 1 else "s")
                host.rings.link = client
                if host.state != "connecting":
                    await host.rings.resync(limits.PING_TIMEOUT)
        await self._drop_unknown_streams(host, client)
        # known from here on: clients of this host get rings there (identify)
        host.client = client
        host.host_id = info.host_id
        host.data_port = (configured.data_port if configured is not None
                          and configured.data_port else info.data_port)
        host.local = local
        host.state, host.error, host.since = "up", "", time.monotonic()
        log.info("host %r is up: ln_daemon with host id %r, data port %d%s", host.name,
                 host.host_id, host.data_port, " (the manager's host)" if host.local else "")
        if host.local:
            self.core.local.host = host.name
        self._identified.set()
        self._identified = asyncio.Event()
        self.streams.host_up(host.name)  # a new daemon knows none of them

    async def _drop_unknown_streams(self, host: HostState, client: Any) -> None:
        """Remove the streams of this instance on the host's daemon that this manager does
        not have (any more): ended while the host was unreachable, or left by an earlier
        manager of the instance on its own host (which is not purged)."""
        stats, _ = await asyncio.wait_for(client.stream_stats(), limits.PING_TIMEOUT)
        known = self.streams.tokens()
        for stat in stats:
            if stat.token not in known:
                with contextlib.suppress(dw.DaemonError):
                    await asyncio.wait_for(client.stream_remove(stat.token),
                                           limits.PING_TIMEOUT)
                log.info("host %r: removed stream %016x that no topic needs", host.name,
                         stat.token)

    async def down(self, host: HostState, reason: str) -> None:
        """The host is unreachable for `reason`: its link and its rings' link go."""
        if host.state != "unreachable" or host.error != reason:
            log.warning("host %r unreachable: %s", host.name, reason)
        if host.state == "up":
            host.since = time.monotonic()
        host.state, host.error = "unreachable", reason
        client, host.client = host.client, None
        if host.rings is not None:
            host.rings.link = None
            host.rings.down_reason = reason
        if client is not None:
            with contextlib.suppress(Exception):
                await client.close()
        self.streams.host_down(host.name, reason)
