"""The manager's view of its hosts and the topic streams between them (docs/network.md),
one class per job, put together by `Network` for core.py (core.HostRings), the runner and
the console:

  monitor.HostMonitor     the daemon link of every host: reconnecting, pinging, host ids
  client_hosts.ClientHosts which host a client runs on: its rings, a provider's address
  plan.StreamPlan         which streams must exist (routes through gateways, transports)
  streams.Forwarding      makes the daemons' streams match the plan; their counters
"""

from __future__ import annotations

import asyncio
import logging
from typing import Any

from ... import _adminlib
from ...naming import sanitize_instance
from ..config import model
from ..processes import daemon_wire as dw
from ..processes.daemons import DaemonPool
from ..registry.core import Core
from ..registry.model import Client, Topic
from ..registry.rings import Rings
from . import limits
from .client_hosts import ClientHosts
from .monitor import HostMonitor, HostState, config_hosts
from .plan import SUBSCRIBE_TCP, SUBSCRIBE_UDP, StreamPlan
from .streams import Forwarding, Stream

__all__ = ["SUBSCRIBE_TCP", "SUBSCRIBE_UDP", "HostState", "Network", "Stream"]

log = logging.getLogger("ln_manager")


class Network:
    """Implements core.HostRings; runs the host monitors and the stream reconciler."""

    def __init__(self, config: model.Config, core: Core, pool: DaemonPool,
                 instance: str) -> None:
        self.config = config
        self.core = core
        self.pool = pool
        local_id = _adminlib.host_id()
        self.hosts: dict[str, HostState] = config_hosts(config, sanitize_instance(instance))
        self.clients = ClientHosts(self.hosts, config, core, pool, local_id)
        self.plan = StreamPlan(config, core, self.clients)
        self.forwarding = Forwarding(self.hosts, core, self.clients, self.plan)
        self.monitor = HostMonitor(self.hosts, config, core, pool, local_id, self.forwarding)
        self._tasks: list[asyncio.Task[None]] = []

    @property
    def streams(self) -> dict[tuple[int, str, str], Stream]:
        return self.forwarding.streams

    @property
    def problems(self) -> dict[tuple[int, str, str], str]:
        return self.plan.problems

    # ---- core.HostRings -------------------------------------------------------------------
    def rings_for(self, client: Client) -> Rings:
        return self.clients.rings_for(client)

    def all_rings(self) -> list[Rings]:
        return self.clients.all_rings()

    def host_label(self, client: Client) -> str:
        return self.clients.host_label(client)

    def local_name(self) -> str:
        return self.clients.local_name()

    def service_host(self, caller: Client, provider: Client, tcp_host: str) -> str:
        return self.clients.service_host(caller, provider, tcp_host)

    async def identify(self, client: Client) -> None:
        await self.monitor.identify(client.host_id)

    def transit_needed(self, topic: Topic, rings: Rings) -> bool:
        return self.forwarding.transit_needed(topic, rings)

    async def published(self, topic: Topic) -> int | None:
        """The newest sequence number of the topic's ring on its publishers' host, asked of
        that host's daemon now (the last answer while it cannot be asked); None when the
        manager's own host counts it, or no host does."""
        name = self.plan.publisher_host(topic) or self.plan.origins.get(topic.id)
        host = self.hosts.get(name) if name is not None else None
        if host is None or host.local or host.rings is None or not host.rings.has(topic.id):
            return None
        client = host.client
        if host.state == "up" and client is not None:
            try:
                host.published[topic.id] = await asyncio.wait_for(
                    client.ring_write_seq(host.rings.current(topic.id)), limits.PING_TIMEOUT)
            except (dw.DaemonError, OSError, TimeoutError) as exc:
                log.debug("host %r: sequence number of topic %r: %s", host.name, topic.name,
                          limits.reason(exc))
        return host.published.get(topic.id, 0)

    # ---- streams --------------------------------------------------------------------------
    def desired(self) -> dict[tuple[int, str, str], tuple[str, str, bool]]:
        """(topic id, src, dst) -> (transport, address, final) of every needed hop."""
        return self.plan.desired()

    async def reconcile(self) -> None:
        await self.forwarding.reconcile()

    # ---- life -----------------------------------------------------------------------------
    def configure(self, config: model.Config) -> None:
        """Use a reloaded configuration's routes and topic transports from now on."""
        self.config = config
        self.clients.config = self.plan.config = self.monitor.config = config

    def start(self) -> None:
        loop = asyncio.get_running_loop()
        self.core.listeners.append(self.forwarding.dirty.set)
        for host in self.hosts.values():
            self._tasks.append(loop.create_task(self.monitor.run(host)))
        self._tasks.append(loop.create_task(self.forwarding.run()))

    async def close(self) -> None:
        """Stop monitoring and reconciling, then remove every stream of this instance from
        the reachable daemons."""
        self.monitor.closing = self.forwarding.closing = True
        for task in self._tasks:
            task.cancel()
        # Python 3.11's wait_for can swallow a cancellation that meets a call's answer: the
        # loops also end on `closing`, after their current wait.
        await asyncio.gather(*self._tasks, return_exceptions=True)
        await self.forwarding.remove_all()

    # ---- listings -------------------------------------------------------------------------
    def host_listing(self) -> list[dict[str, Any]]:
        out = []
        for host in self.hosts.values():
            info = host.info()
            unknown, malformed = self.forwarding.totals.get(host.name, (0, 0))
            info["unknown_stream"], info["malformed"] = unknown, malformed
            out.append(info)
        return out

    def stream_listing(self) -> dict[str, Any]:
        streams = [s.info() for s in sorted(self.streams.values(),
                                            key=lambda s: (s.topic, s.src, s.dst))]
        pairs: dict[tuple[str, str], dict[str, Any]] = {}
        for s in streams:
            pair = pairs.setdefault((s["src"], s["dst"]), {
                "src": s["src"], "dst": s["dst"], "topics": 0, "msgs_per_s": 0.0,
                "bytes_per_s": 0, "drops": 0})
            pair["topics"] += 1
            pair["msgs_per_s"] = round(pair["msgs_per_s"] + s["msgs_per_s"], 1)
            pair["bytes_per_s"] += s["bytes_per_s"]
            pair["drops"] += s["drops"]
        topics = {t.id: t.name for t in self.core.registry.topics.values()}
        problems = [{"topic": topics.get(k[0], "?"), "src": k[1], "dst": k[2], "error": text}
                    for k, text in sorted(self.problems.items())]
        return {"streams": streams, "pairs": list(pairs.values()), "problems": problems}
