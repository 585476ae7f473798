"""Makes the daemons' topic streams match the plan (plan.py): installs and removes them
(with the rings a gateway host needs), keeps trying the ones a host is not ready for,
drops rings nothing needs any more, and turns the daemons' stream counters into rates."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import secrets
import time
from dataclasses import dataclass, field
from typing import Any

from ..processes import daemon_wire as dw
from ..registry.core import Core
from ..registry.model import RequestError, Topic
from ..registry.rings import Rings
from . import limits
from .client_hosts import ClientHosts
from .monitor import HostState
from .plan import StreamKey, StreamPlan

log = logging.getLogger("ln_manager")


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
                "stale": r.stale if r else 0, "invalid": r.invalid if r else 0,
                "rejected": r.rejected if r else 0}


class Forwarding:
    """The streams this manager has asked the daemons for; implements monitor.HostStreams."""

    def __init__(self, hosts: dict[str, HostState], core: Core, clients: ClientHosts,
                 plan: StreamPlan) -> None:
        self.hosts = hosts
        self.core = core
        self.clients = clients
        self.plan = plan
        self.streams: dict[StreamKey, Stream] = {}
        self.totals: dict[str, tuple[int, int]] = {}  # host -> unknown, malformed
        self.dirty = asyncio.Event()
        self.closing = False

    def security(self) -> str:
        """The instance's protection of forwarded data (docs/security.md), the same for both
        ends of every stream; a reloaded configuration that changes it installs them again."""
        return self.plan.config.instance.security or dw.DEFAULT_SECURITY

    # ---- what the host monitor tells ------------------------------------------------------
    def tokens(self) -> set[int]:
        return {s.token for s in self.streams.values()}

    def host_up(self, name: str) -> None:
        """A new daemon on host `name`: it knows none of the streams.  Those it sends get new
        receiving ends as well: its UDP salts start from its clock again, which may have
        gone back, and a receiver takes no salt older than the last one it saw."""
        for stream in self.streams.values():
            if stream.src == name:
                stream.installed_src = None
                stream.installed_dst = None
            if stream.dst == name:
                stream.installed_dst = None
        self.dirty.set()

    def host_down(self, name: str, reason: str) -> None:
        for stream in self.streams.values():
            if name in (stream.src, stream.dst):
                stream.error = f"host {name!r} unreachable: {reason}"

    def take_stats(self, host: HostState, stats: list[Any], totals: Any) -> None:
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

    # ---- reconciling ----------------------------------------------------------------------
    async def run(self) -> None:
        """Reconcile after every change, and every POLL_INTERVAL while a stream waits."""
        while not self.closing:
            if all(s.installed_src and s.installed_dst for s in self.streams.values()):
                await self.dirty.wait()
            else:  # a stream waits for a host or was refused: try it again in a while
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(self.dirty.wait(), limits.POLL_INTERVAL)
            self.dirty.clear()
            try:
                await self.reconcile()
            except asyncio.CancelledError:
                raise
            except Exception:
                log.exception("forwarding: reconciling the streams failed")

    async def reconcile(self) -> None:
        want = self.plan.desired()
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

    def transit_needed(self, topic: Topic, rings: Rings) -> bool:
        """Whether the topic's ring on that host must stay although no port of the topic is
        left there: it passes samples on to other hosts (a gateway, which may have had
        subscribers of its own), or its publishers ran there.  That ring counts the topic's
        sequence numbers; made anew, it would count from 1 again, and every other host
        would drop a returning publisher's samples as stale until it passed the old count.
        It stays until the topic ends or a publisher runs on another host."""
        if self.plan.origins.get(topic.id) == rings.host:
            return True
        return any(s.topic_id == topic.id
                   and (s.src == rings.host or (s.dst == rings.host and not s.final))
                   for s in self.streams.values())

    def _daemon(self, name: str) -> HostState | None:
        host = self.hosts.get(name)
        return host if host is not None and host.state == "up" else None

    async def _install(self, stream: Stream, topic: Topic) -> None:
        src, dst = self._daemon(stream.src), self._daemon(stream.dst)
        if src is None or dst is None:
            down = stream.src if src is None else stream.dst
            if down in self.hosts:
                why = self.hosts[down].error or self.hosts[down].state
            elif down == self.clients.local_name():
                why = ("the manager's own host is no host of the configuration: name it in "
                       "'hosts' and run an ln_daemon there")
            else:
                why = "not a configured host"
            stream.error = f"waiting for host {down!r}: {why}"
            return
        # the links of now: one that goes while we wait fails our calls, not the round
        src_client, dst_client = src.client, dst.client
        src_rings = self.clients.rings_of(stream.src)
        dst_rings = self.clients.rings_of(stream.dst)
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
        security = self.security()
        try:
            want_dst = (dst_rings.current(topic.id), stream.transport, security)
            if stream.installed_dst != want_dst:
                await dst_client.stream_recv(stream.token, want_dst[0], topic.layout_hash,
                                             topic.message_size, stream.transport, security)
                stream.installed_dst = want_dst
            if not src_rings.has(topic.id):
                return  # gone while the daemon answered; that change runs us again
            want_src = (src_rings.current(topic.id), stream.transport, stream.address,
                        dst.data_port, security)
            if stream.installed_src != want_src:
                await src_client.stream_send(stream.token, want_src[0], topic.layout_hash,
                                             topic.message_size, stream.transport,
                                             stream.address, dst.data_port, security)
                stream.installed_src = want_src
            stream.error = ""
        except (dw.DaemonError, OSError) as exc:
            reason = limits.reason(exc)
            if stream.error != reason:  # tried again every POLL_INTERVAL: once
                log.warning("forwarding topic %r from %r to %r: %s", topic.name, stream.src,
                            stream.dst, reason)
            stream.error = reason

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
                rings = self.clients.rings_of(host.name)
                if rings is None:
                    continue
                for topic_id in rings.topic_ids():
                    topic = topics.get(topic_id)
                    if topic is not None and (
                            any(self.clients.client_host(p.client) == host.name
                                for p in topic.ports.values())
                            or self.transit_needed(topic, rings)):
                        continue
                    await rings.remove(topic_id)

    async def remove_all(self) -> None:
        """Remove every stream of this instance from the reachable daemons (after
        core.shutdown, which removed the rings): also those the reconciler was setting up
        when it was stopped, which it had not recorded yet."""
        for host in self.hosts.values():
            client = host.client
            if host.state != "up" or client is None:
                continue  # its streams are purged by the next manager of the instance
            try:
                stats, _ = await asyncio.wait_for(client.stream_stats(), limits.PING_TIMEOUT)
                for stat in stats:
                    with contextlib.suppress(dw.DaemonError):
                        await asyncio.wait_for(client.stream_remove(stat.token),
                                               limits.PING_TIMEOUT)
            except (dw.DaemonError, OSError, TimeoutError) as exc:
                log.warning("host %r: cannot remove the streams of this instance: %s",
                            host.name, limits.reason(exc))
        self.streams.clear()
