"""The manager's view of its hosts and the topic streams between them (docs/network.md).

Keeps a link to the ln_daemon of every host of the configuration (reconnecting, pinging,
marking a host unreachable with the reason), learns each host's id and data port, gives
core.py the rings of a client's host, and makes the daemons forward every topic from the
host of its publishers to each host with subscribers (through gateway hosts where the
`network` sections say so).  Polls the daemons' stream counters into per-topic and
per-host-pair rates for the console and the scripting API."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import secrets
import socket
import time
from dataclasses import dataclass, field
from typing import Any

from ... import _adminlib
from ..processes import daemon_wire as dw
from . import routes
from ..config import model
from ..registry.core import Core
from ..processes.daemons import DaemonPool
from ..registry.model import Client, PortKind, RequestError, Topic
from ..registry.rings import RemoteRings, Rings
from ... import transports
from ...addresses import is_loopback
from ...naming import sanitize_instance

log = logging.getLogger("ln_manager")

POLL_INTERVAL = 1.0  # seconds between pings / counter polls of one daemon
PING_TIMEOUT = 3.0  # a daemon that does not answer within this is unreachable
CONNECT_TIMEOUT = 3.0
# How long a port request waits for its client's host to be known: well below libln's
# request timeout (10 s), so that the client gets the explanation, not a timeout.
IDENTIFY_TIMEOUT = 5.0
SUBSCRIBE_UDP = 0x100  # LN_SUBSCRIBE_UDP
SUBSCRIBE_TCP = 0x200  # LN_SUBSCRIBE_TCP


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


@dataclass
class _Side:
    """Counters of one end of a stream, and their rates."""

    stat: Any = None  # dw.StreamStat
    at: float = 0.0
    samples_per_s: float = 0.0
    bytes_per_s: float = 0.0

    def update(self, stat: Any, now: float) -> None:
        if self.stat is not None and now > self.at:
            dt = now - self.at
            self.samples_per_s = max(0, stat.samples - self.stat.samples) / dt
            self.bytes_per_s = max(0, stat.bytes - self.stat.bytes) / dt
        self.stat, self.at = stat, now


@dataclass(eq=False)
class Stream:
    """One topic's samples from host `src` to host `dst` (one hop of a route)."""

    topic_id: int
    topic: str
    src: str
    dst: str
    token: int
    transport: str
    address: str
    final: bool  # dst has subscribers (not only a gateway)
    installed_src: tuple[Any, ...] | None = None
    installed_dst: tuple[Any, ...] | None = None
    error: str = ""
    send: _Side = field(default_factory=_Side)
    recv: _Side = field(default_factory=_Side)

    def info(self) -> dict[str, Any]:
        s, r = self.send.stat, self.recv.stat
        return {"topic": self.topic, "src": self.src, "dst": self.dst,
                "transport": self.transport, "token": f"{self.token:016x}",
                "active": self.installed_src is not None and self.installed_dst is not None,
                "error": self.error or (s.last_error if s else "") or
                (r.last_error if r else ""),
                "connected": bool(s.connected) if s else False,
                "sent": s.samples if s else 0, "received": r.samples if r else 0,
                "msgs_per_s": round(self.recv.samples_per_s if r else
                                    self.send.samples_per_s, 1),
                "bytes_per_s": round(self.recv.bytes_per_s if r else self.send.bytes_per_s),
                "send_drops": s.drops if s else 0, "recv_drops": r.drops if r else 0,
                "drops": (s.drops if s else 0) + (r.drops if r else 0),
                "stale": r.stale if r else 0, "invalid": r.invalid if r else 0}


class Network:
    """Implements core.HostRings; runs the host monitors and the stream reconciler."""

    def __init__(self, config: model.Config, core: Core, pool: DaemonPool,
                 instance: str) -> None:
        self.config = config
        self.core = core
        self.pool = pool
        self.prefix = sanitize_instance(instance)
        self.local_id = _adminlib.host_id()
        self.hosts: dict[str, HostState] = {}
        for index, (name, node) in enumerate(routes.config_hosts(config), start=1):
            host = HostState(name, node)
            host.rings = RemoteRings(name, self.prefix, f"h{index}")
            self.hosts[name] = host
        self.streams: dict[tuple[int, str, str], Stream] = {}
        self.problems: dict[tuple[int, str, str], str] = {}  # no route etc.
        # topic id -> the host of its publishers, also after they left: its ring there
        # holds the topic's sequence number (see transit_needed)
        self.origins: dict[int, str] = {}
        self.totals: dict[str, tuple[int, int]] = {}  # host -> unknown, malformed
        self._dirty = asyncio.Event()
        self._identified = asyncio.Event()  # set (and replaced) whenever a host comes up
        self._tasks: list[asyncio.Task[None]] = []
        self._closing = False

    # ---- core.HostRings -------------------------------------------------------------------
    def _host_of(self, client: Client) -> HostState | None:
        """The client's host; None for the manager's own."""
        if not client.host_id or client.host_id == self.local_id:
            return None
        for host in self.hosts.values():
            if host.host_id == client.host_id:
                return None if host.local else host
        known = ", ".join(f"{h.name}={h.host_id or '?'}" for h in self.hosts.values())
        raise RequestError("ENOTFOUND", f"client {client.name!r} runs on host id "
                           f"{client.host_id!r}, which is none of this manager's hosts "
                           f"({known}); name its host in the configuration and run an "
                           f"ln_daemon there")

    def rings_for(self, client: Client) -> Rings:
        host = self._host_of(client)
        if host is None:
            return self.core.local
        assert host.rings is not None
        return host.rings

    def all_rings(self) -> list[Rings]:
        return [self.core.local] + [h.rings for h in self.hosts.values()
                                    if h.rings is not None and not h.local]

    def host_label(self, client: Client) -> str:
        try:
            host = self._host_of(client)
        except RequestError:
            return client.host_id
        return host.name if host is not None else self.local_name()

    def local_name(self) -> str:
        for host in self.hosts.values():
            if host.local:
                return host.name
        for host in self.hosts.values():
            if self.pool.is_local(host.node):
                return host.name
        for host in self.hosts.values():  # before its daemon answered: by its addresses
            configured = self.config.hosts.get(host.name)
            if configured and any(_own_address(a) for a in configured.interfaces.values()):
                return host.name
        return "localhost"

    def service_host(self, caller: Client, provider: Client, tcp_host: str) -> str:
        if not is_loopback(tcp_host) and tcp_host.strip("[]") not in ("0.0.0.0", "::"):
            return tcp_host
        src, dst = self._client_host(caller), self._client_host(provider)
        if src is None or dst is None or src == dst:
            return tcp_host
        target = routes.host_address(self.config, src, dst)
        if (target is None or target in routes.LOCAL_NAMES) and dst == self.local_name() \
                and src in self.hosts:
            # the manager's host, which the configuration gives no address: the one its
            # connection to the caller's daemon comes from
            target = self.pool.local_address(self.hosts[src].node)
        return target or tcp_host

    def _known(self, host_id: str) -> bool:
        return (not host_id or host_id == self.local_id
                or any(h.host_id == host_id for h in self.hosts.values()))

    async def identify(self, client: Client) -> None:
        loop = asyncio.get_running_loop()
        deadline = loop.time() + IDENTIFY_TIMEOUT
        while not self._known(client.host_id):
            left = deadline - loop.time()
            if left <= 0 or all(h.state == "up" for h in self.hosts.values()):
                return  # rings_for tells the client why its host is unknown
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._identified.wait(), min(left, POLL_INTERVAL))

    def transit_needed(self, topic: Topic, rings: Rings) -> bool:
        """Whether the topic's ring on that host must stay although no port of the topic is
        left there: it passes samples on to other hosts (a gateway, which may have had
        subscribers of its own), or its publishers ran there.  That ring counts the topic's
        sequence numbers; made anew, it would count from 1 again, and every other host
        would drop a returning publisher's samples as stale until it passed the old count.
        It stays until the topic ends or a publisher runs on another host."""
        if self.origins.get(topic.id) == rings.host:
            return True
        return any(s.topic_id == topic.id
                   and (s.src == rings.host or (s.dst == rings.host and not s.final))
                   for s in self.streams.values())

    async def published(self, topic: Topic) -> int | None:
        """The newest sequence number of the topic's ring on its publishers' host, asked of
        that host's daemon now (the last answer while it cannot be asked); None when the
        manager's own host counts it, or no host does."""
        name = self._publisher_host(topic) or self.origins.get(topic.id)
        host = self.hosts.get(name) if name is not None else None
        if host is None or host.local or host.rings is None or not host.rings.has(topic.id):
            return None
        client = host.client
        if host.state == "up" and client is not None:
            try:
                host.published[topic.id] = await asyncio.wait_for(
                    client.ring_write_seq(host.rings.current(topic.id)), PING_TIMEOUT)
            except (dw.DaemonError, OSError, TimeoutError) as exc:
                log.debug("host %r: sequence number of topic %r: %s", host.name, topic.name,
                          _reason(exc))
        return host.published.get(topic.id, 0)

    # ---- life -----------------------------------------------------------------------------
    def configure(self, config: model.Config) -> None:
        """Use a reloaded configuration's routes and topic transports from now on."""
        self.config = config

    def start(self) -> None:
        loop = asyncio.get_running_loop()
        self.core.listeners.append(self._dirty.set)
        for host in self.hosts.values():
            self._tasks.append(loop.create_task(self._monitor(host)))
        self._tasks.append(loop.create_task(self._reconciler()))

    async def close(self) -> None:
        """Stop monitoring and reconciling, then remove every stream of this instance from
        the reachable daemons (after core.shutdown, which removed the rings): also those the
        reconciler was setting up when it was stopped, which it had not recorded yet."""
        self._closing = True
        for task in self._tasks:
            task.cancel()
        # Python 3.11's wait_for can swallow a cancellation that meets a call's answer: the
        # loops also end on _closing, after their current wait.
        await asyncio.gather(*self._tasks, return_exceptions=True)
        for host in self.hosts.values():
            client = host.client
            if host.state != "up" or client is None:
                continue  # its streams are purged by the next manager of the instance
            try:
                stats, _ = await asyncio.wait_for(client.stream_stats(), PING_TIMEOUT)
                for stat in stats:
                    with contextlib.suppress(dw.DaemonError):
                        await asyncio.wait_for(client.stream_remove(stat.token), PING_TIMEOUT)
            except (dw.DaemonError, OSError, TimeoutError) as exc:
                log.warning("host %r: cannot remove the streams of this instance: %s",
                            host.name, _reason(exc))
        self.streams.clear()

    # ---- monitoring -----------------------------------------------------------------------
    async def _monitor(self, host: HostState) -> None:
        while not self._closing:
            try:
                await self._check(host)
            except asyncio.CancelledError:
                raise
            except Exception as exc:  # DaemonError, OSError, TimeoutError, ...
                await self._down(host, _reason(exc))
            await asyncio.sleep(POLL_INTERVAL)

    async def _check(self, host: HostState) -> None:
        client = await asyncio.wait_for(self.pool.link(host.node), CONNECT_TIMEOUT)
        if client is not host.client:
            await self._up(host, client)
        await asyncio.wait_for(client.ping(), PING_TIMEOUT)
        stats, totals = await asyncio.wait_for(client.stream_stats(), PING_TIMEOUT)
        self._take_stats(host, stats, totals)

    async def _up(self, host: HostState, client: Any) -> None:
        info = await asyncio.wait_for(client.net_info(), PING_TIMEOUT)
        configured = self.config.hosts.get(host.name)
        local = info.host_id == self.local_id
        if not local and host.rings is not None:
            # No ring of the host changes meanwhile; every call is bounded, since client
            # requests wait for the lock and this monitor is what gives up on a daemon.
            async with self.core.transit():
                if not host.purged:
                    # segments and streams an earlier manager of this instance left there
                    removed = await asyncio.wait_for(client.ring_purge(), PING_TIMEOUT)
                    host.purged = True
                    if removed:
                        log.info("host %r: removed %d stale segment%s of this instance",
                                 host.name, removed, "" if removed == 1 else "s")
                host.rings.link = client
                if host.state != "connecting":
                    await host.rings.resync(PING_TIMEOUT)
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
        for stream in self.streams.values():  # a new daemon knows none of them
            if stream.src == host.name:
                stream.installed_src = None
            if stream.dst == host.name:
                stream.installed_dst = None
        self._dirty.set()

    async def _drop_unknown_streams(self, host: HostState, client: Any) -> None:
        """Remove the streams of this instance on the host's daemon that this manager does
        not have (any more): ended while the host was unreachable, or left by an earlier
        manager of the instance on its own host (which is not purged)."""
        stats, _ = await asyncio.wait_for(client.stream_stats(), PING_TIMEOUT)
        known = {s.token for s in self.streams.values()}
        for stat in stats:
            if stat.token not in known:
                with contextlib.suppress(dw.DaemonError):
                    await asyncio.wait_for(client.stream_remove(stat.token), PING_TIMEOUT)
                log.info("host %r: removed stream %016x that no topic needs", host.name,
                         stat.token)

    async def _down(self, host: HostState, reason: str) -> None:
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
        for stream in self.streams.values():
            if host.name in (stream.src, stream.dst):
                stream.error = f"host {host.name!r} unreachable: {reason}"

    def _take_stats(self, host: HostState, stats: list[Any], totals: Any) -> None:
        now = time.monotonic()
        by_token = {s.token: s for s in self.streams.values()}
        for stat in stats:
            stream = by_token.get(stat.token)
            if stream is None:
                continue
            if stat.sending and stream.src == host.name:
                stream.send.update(stat, now)
            elif not stat.sending and stream.dst == host.name:
                stream.recv.update(stat, now)
        self.totals[host.name] = (totals.unknown_stream, totals.malformed)

    # ---- streams --------------------------------------------------------------------------
    async def _reconciler(self) -> None:
        while not self._closing:
            if all(s.installed_src and s.installed_dst for s in self.streams.values()):
                await self._dirty.wait()
            else:  # a stream waits for a host or was refused: try it again in a while
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(self._dirty.wait(), POLL_INTERVAL)
            self._dirty.clear()
            try:
                await self.reconcile()
            except asyncio.CancelledError:
                raise
            except Exception:
                log.exception("forwarding: reconciling the streams failed")

    def _client_host(self, client: Client) -> str | None:
        try:
            host = self._host_of(client)
        except RequestError:
            return None
        return host.name if host is not None else self.local_name()

    def _publisher_host(self, topic: Topic) -> str | None:
        hosts = {self._client_host(p.client) for p in topic.ports.values()
                 if p.kind is PortKind.PUBLISHER}
        return next(iter(hosts)) if len(hosts) == 1 else None

    def _transport(self, topic: Topic, host: str) -> str:
        """TCP if a subscription on `host` asks for it, else UDP if one asks for that, else
        the configuration's setting for the topic, else UDP."""
        flags = 0
        for port in topic.ports.values():
            if port.kind is PortKind.SUBSCRIBER and self._client_host(port.client) == host:
                flags |= port.flags
        return (transports.asked(flags, udp_flag=SUBSCRIBE_UDP, tcp_flag=SUBSCRIBE_TCP)
                or model.topic_transport(self.config, topic.name) or transports.DEFAULT_FORWARD)

    def desired(self) -> dict[tuple[int, str, str], tuple[str, str, bool]]:
        """(topic id, src, dst) -> (transport, address, final) of every needed hop."""
        want: dict[tuple[int, str, str], tuple[str, str, bool]] = {}
        self.problems = {}
        topics = self.core.registry.topics.values()
        self.origins = {t.id: self.origins[t.id] for t in topics if t.id in self.origins}
        for topic in topics:
            src = self._publisher_host(topic)
            if src is None:
                continue
            self.origins[topic.id] = src
            sinks = {self._client_host(p.client) for p in topic.ports.values()
                     if p.kind is PortKind.SUBSCRIBER} - {src, None}
            for dst in sorted(h for h in sinks if h is not None):
                transport = self._transport(topic, dst)
                try:
                    hops = routes.route(self.config, src, dst)
                except routes.NoRoute as exc:
                    self.problems[(topic.id, src, dst)] = str(exc)
                    continue
                for hop in hops:
                    key = (topic.id, hop.src, hop.dst)
                    final = hop.dst == dst or want.get(key, ("", "", False))[2]
                    old = want.get(key)
                    if old is not None and old[0] == transports.TCP:
                        transport = transports.TCP
                    want[key] = (transport, hop.address, final)
        return want

    async def reconcile(self) -> None:
        want = self.desired()
        live = {t.id for t in self.core.registry.topics.values()}
        for host in self.hosts.values():  # the last sequence numbers of ended topics
            for topic_id in [t for t in host.published if t not in live]:
                del host.published[topic_id]
        for key in [k for k in self.streams if k not in want]:
            stream = self.streams.pop(key)
            await self._uninstall(stream)
            log.info("forwarding of topic %r from %r to %r ended", stream.topic, stream.src,
                     stream.dst)
        topics = {t.id: t for t in self.core.registry.topics.values()}
        for key, (transport, address, final) in want.items():
            topic = topics.get(key[0])
            if topic is None:
                continue  # ended while streams were removed; that change runs us again
            stream = self.streams.get(key)
            if stream is None or stream.transport != transport:
                if stream is not None:
                    await self._uninstall(stream)
                stream = Stream(topic.id, topic.name, key[1], key[2],
                                secrets.randbits(63) | 1, transport, address, final)
                self.streams[key] = stream
                log.info("forwarding topic %r from %r to %r over %s", topic.name, key[1],
                         key[2], transport.upper())
            stream.address, stream.final = address, final
            await self._install(stream, topic)
        await self._drop_transit_rings()

    def _rings_of(self, name: str) -> Rings | None:
        host = self.hosts.get(name)
        if host is None or host.local:
            return self.core.local if name == self.local_name() else None
        return host.rings

    def _daemon(self, name: str) -> HostState | None:
        host = self.hosts.get(name)
        return host if host is not None and host.state == "up" else None

    async def _install(self, stream: Stream, topic: Topic) -> None:
        src, dst = self._daemon(stream.src), self._daemon(stream.dst)
        if src is None or dst is None:
            down = stream.src if src is None else stream.dst
            if down in self.hosts:
                why = self.hosts[down].error or self.hosts[down].state
            elif down == self.local_name():
                why = ("the manager's own host is no host of the configuration: name it in "
                       "'hosts' and run an ln_daemon there")
            else:
                why = "not a configured host"
            stream.error = f"waiting for host {down!r}: {why}"
            return
        # the links of now: one that goes while we wait fails our calls, not the round
        src_client, dst_client = src.client, dst.client
        src_rings, dst_rings = self._rings_of(stream.src), self._rings_of(stream.dst)
        if src_rings is None or dst_rings is None or not src_rings.has(topic.id):
            stream.error = "no ring on the sending host yet"
            return
        async with self.core.transit():
            if self.core.registry.topics.get(topic.name) is not topic \
                    or not src_rings.has(topic.id):
                return  # gone while we waited for the core; that change runs us again
            if not dst_rings.has(topic.id):  # a gateway: a ring that only passes samples on
                try:
                    await dst_rings.create(topic.id, topic.name, topic.md_name,
                                           topic.layout_hash, topic.message_size,
                                           topic.slots)
                    await dst_rings.set_counts(topic.id, topic.publishers, topic.subscribers)
                except RequestError as exc:
                    stream.error = exc.text
                    return
        try:
            want_dst = (dst_rings.current(topic.id), stream.transport)
            if stream.installed_dst != want_dst:
                await dst_client.stream_recv(stream.token, want_dst[0], topic.layout_hash,
                                             topic.message_size, stream.transport)
                stream.installed_dst = want_dst
            if not src_rings.has(topic.id):
                return  # gone while the daemon answered; that change runs us again
            want_src = (src_rings.current(topic.id), stream.transport, stream.address,
                        dst.data_port)
            if stream.installed_src != want_src:
                await src_client.stream_send(stream.token, want_src[0], topic.layout_hash,
                                             topic.message_size, stream.transport,
                                             stream.address, dst.data_port)
                stream.installed_src = want_src
            stream.error = ""
        except (dw.DaemonError, OSError) as exc:
            if stream.error != _reason(exc):  # tried again every POLL_INTERVAL: once
                log.warning("forwarding topic %r from %r to %r: %s", topic.name, stream.src,
                            stream.dst, _reason(exc))
            stream.error = _reason(exc)

    async def _uninstall(self, stream: Stream) -> None:
        for name, installed in ((stream.src, stream.installed_src),
                                (stream.dst, stream.installed_dst)):
            host = self._daemon(name)
            if installed is not None and host is not None:
                with contextlib.suppress(Exception):
                    await host.client.stream_remove(stream.token)
        stream.installed_src = stream.installed_dst = None

    async def _drop_transit_rings(self) -> None:
        """Remove the rings that neither a port nor a stream needs any more, on every host
        (the manager's own included): gateway rings no stream passes through, and rings of
        topics that ended while the reconciler set up their streams."""
        async with self.core.transit():
            topics = {t.id: t for t in self.core.registry.topics.values()}
            for host in self.hosts.values():
                rings = self._rings_of(host.name)
                if rings is None:
                    continue
                for topic_id in rings.topic_ids():
                    topic = topics.get(topic_id)
                    if topic is not None and (
                            any(self._client_host(p.client) == host.name
                                for p in topic.ports.values())
                            or self.transit_needed(topic, rings)):
                        continue
                    await rings.remove(topic_id)

    # ---- listings -------------------------------------------------------------------------
    def host_listing(self) -> list[dict[str, Any]]:
        out = []
        for host in self.hosts.values():
            info = host.info()
            unknown, malformed = self.totals.get(host.name, (0, 0))
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


def _own_address(address: str) -> bool:
    """True if `address` is one of this machine's (this network namespace's) addresses."""
    family = socket.AF_INET6 if ":" in address else socket.AF_INET
    try:
        with socket.socket(family, socket.SOCK_DGRAM) as sock:
            sock.bind((address, 0))
    except OSError:
        return False
    return True


def _reason(exc: BaseException) -> str:
    if isinstance(exc, TimeoutError | asyncio.TimeoutError):
        return "no answer from its ln_daemon"
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    return str(exc) or type(exc).__name__
