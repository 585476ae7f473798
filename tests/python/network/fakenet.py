"""The manager's network side (network.Network with core.Core) against fake ln_daemons, for
tests that must interleave the reconciler, the host monitors and client requests exactly.

A FakeDaemon keeps what a real one would: segments in its host's /dev/shm (each creation a
new object, so a stream that still maps a removed segment is told apart from its successor
of the same name), the rings it holds, reader slots, counts and streams (a stream maps its
ring's segment when it is set up, as the daemon's taps do).  Requests take effect when
they arrive; `gate(name)` holds back the *reply* of the next such call until the test
releases it, as a slow daemon would.  FakePool hands out one FakeLink per connection; a
daemon made unreachable fails its link's calls and refuses new links."""

from __future__ import annotations

import asyncio
import itertools
from dataclasses import dataclass, field
from typing import Any

from links_and_nodes import _adminlib
from links_and_nodes.manager.config import parse_text
from links_and_nodes.manager.network import limits
from links_and_nodes.manager.network.hosts import Network
from links_and_nodes.manager.processes import daemon_wire as dw
from links_and_nodes.manager.registry.core import Core, Session
from links_and_nodes.manager.registry.model import Registry
from links_and_nodes.manager.registry.services import Services
from links_and_nodes.tools import protocol as p

_serial = itertools.count(1)
MD = "nettest/sample"
HASH = 0x1234
SIZE = 16


@dataclass(eq=False)
class Seg:
    """One segment in a host's /dev/shm."""

    name: str
    slots: int
    serial: int = field(default_factory=lambda: next(_serial))
    linked: bool = True
    seq: int = 0
    successor: Seg | None = None
    readers: dict[int, tuple[int, int]] = field(default_factory=dict)
    counts: tuple[int, int] = (0, 0)

    def newest(self) -> Seg:
        seg = self
        while seg.successor is not None:
            seg = seg.successor
        return seg


@dataclass(eq=False)
class FakeStream:
    token: int
    sending: bool
    ring: str
    seg: Seg
    transport: str
    peer: str = ""


class FakeDaemon:
    def __init__(self, host_id: str, data_port: int = 54377) -> None:
        self.host_id = host_id
        self.data_port = data_port
        self.shm: dict[str, Seg] = {}
        self.held: dict[str, Seg] = {}
        self.streams: dict[int, FakeStream] = {}
        self.security: dict[int, str] = {}  # token -> the level the manager asked for
        self.reachable = True
        self.links: list[FakeLink] = []
        self._gates: dict[str, asyncio.Event] = {}
        self.entered: dict[str, asyncio.Event] = {}

    # ---- test controls ------------------------------------------------------------------
    def gate(self, call: str) -> tuple[asyncio.Event, asyncio.Event]:
        """Hold back the reply of the next `call`: (entered, release)."""
        release = asyncio.Event()
        self._gates[call] = release
        self.entered[call] = asyncio.Event()
        return self.entered[call], release

    def restart(self) -> None:
        """The daemon process restarts: its handles, streams and connections go; the
        segments stay in /dev/shm."""
        self.held.clear()
        self.streams.clear()
        for link in self.links:
            link.closed = True

    def segments(self, topic_id: int) -> list[str]:
        """Names of this host's linked segments of a topic."""
        return sorted(n for n in self.shm if n.split(".")[2] == str(topic_id))

    def live(self, stream: FakeStream) -> bool:
        """Whether the stream maps the segment its ring name stands for now."""
        return self.shm.get(stream.ring) is stream.seg and stream.seg.linked

    async def _reply(self, call: str) -> None:
        release = self._gates.pop(call, None)
        if release is not None:
            self.entered[call].set()
            await release.wait()

    def _ring(self, name: str) -> Seg:
        seg = self.held.get(name)
        if seg is None:
            raise dw.DaemonError(f"no ring {name} held", dw.ErrorCode.RING_FAILED)
        return seg

    def _unlink(self, name: str) -> None:
        seg = self.shm.pop(name, None)
        if seg is not None:
            seg.linked = False

    # ---- the requests -------------------------------------------------------------------
    async def net_info(self) -> dw.NetInfo:
        return dw.NetInfo(self.host_id, self.data_port)

    async def ping(self) -> None:
        await self._reply("ping")

    async def ring_purge(self) -> int:
        self.streams.clear()
        self.held.clear()
        count = len(self.shm)
        for name in list(self.shm):
            self._unlink(name)
        return count

    async def ring_create(self, name: str, topic: str, md_name: str, layout_hash: int,
                          message_size: int, slots: int, *, adopt: bool = False) -> None:
        held = self.held.get(name)
        if held is not None and held.linked:
            if not adopt:
                raise dw.DaemonError(f"{name} exists", dw.ErrorCode.RING_FAILED)
        elif name in self.shm:
            if not adopt:
                raise dw.DaemonError(f"{name} exists", dw.ErrorCode.RING_FAILED)
            self.held[name] = self.shm[name]
        else:
            seg = Seg(name, slots)
            self.shm[name] = self.held[name] = seg
        await self._reply("ring_create")

    async def ring_retire(self, old: str, successor: str, timeout: float = 1.0) -> None:
        a, b = self._ring(old), self._ring(successor)
        b.seq, b.readers, b.counts = a.seq, dict(a.readers), a.counts
        a.successor = b
        await self._reply("ring_retire")

    async def ring_reserve_reader(self, name: str, index: int, pid: int, buffers: int) -> None:
        self._ring(name).readers[index] = (pid, buffers)
        await self._reply("ring_reserve_reader")

    async def ring_release_reader(self, name: str, index: int) -> None:
        self._ring(name).readers.pop(index, None)
        await self._reply("ring_release_reader")

    async def ring_set_counts(self, name: str, publishers: int, subscribers: int) -> None:
        self._ring(name).counts = (publishers, subscribers)
        await self._reply("ring_set_counts")

    async def ring_remove(self, name: str) -> None:
        self.held.pop(name, None)
        self._unlink(name)
        await self._reply("ring_remove")

    async def ring_write_seq(self, name: str) -> int:
        seq = self._ring(name).newest().seq
        await self._reply("ring_write_seq")
        return seq

    def _tap(self, ring: str) -> Seg:
        seg = self.shm.get(ring)
        if seg is None:
            raise dw.DaemonError(f"cannot open {ring}", dw.ErrorCode.STREAM_FAILED)
        return seg

    async def stream_send(self, token: int, ring: str, layout_hash: int, message_size: int,
                          transport: str, host: str, port: int,
                          security: str = dw.DEFAULT_SECURITY) -> None:
        self.streams[token] = FakeStream(token, True, ring, self._tap(ring), transport,
                                         f"{host}:{port}")
        self.security[token] = security
        await self._reply("stream_send")

    async def stream_recv(self, token: int, ring: str, layout_hash: int, message_size: int,
                          transport: str, security: str = dw.DEFAULT_SECURITY) -> None:
        self.streams[token] = FakeStream(token, False, ring, self._tap(ring), transport)
        self.security[token] = security
        await self._reply("stream_recv")

    async def stream_remove(self, token: int) -> None:
        if self.streams.pop(token, None) is None:
            raise dw.DaemonError(f"no stream {token:016x}", dw.ErrorCode.UNKNOWN_STREAM)
        await self._reply("stream_remove")

    async def stream_stats(self) -> tuple[list[dw.StreamStat], dw.StreamTotals]:
        stats = [dw.StreamStat(s.token, s.sending, s.transport, s.ring, s.peer, 0, 0, 0, 0, 0,
                               0, True, "") for s in self.streams.values()]
        await self._reply("stream_stats")
        return stats, dw.StreamTotals(0, 0)


class FakeLink:
    """One connection of the manager to a FakeDaemon."""

    def __init__(self, daemon: FakeDaemon) -> None:
        self.daemon = daemon
        self.closed = False
        daemon.links.append(self)

    def __getattr__(self, name: str) -> Any:
        call = getattr(self.daemon, name)

        async def forward(*args: Any, **kwargs: Any) -> Any:
            if self.closed or not self.daemon.reachable:
                raise dw.DaemonConnectionError("connection to the daemon lost")
            return await call(*args, **kwargs)

        return forward

    async def close(self) -> None:
        self.closed = True


class FakePool:
    def __init__(self, daemons: dict[str, FakeDaemon], local: str | None = None) -> None:
        self.daemons = daemons
        self.local = local
        self.links: dict[str, FakeLink] = {}

    def is_local(self, node: str) -> bool:
        return node == self.local

    async def link(self, node: str) -> FakeLink:
        link = self.links.get(node)
        if link is not None and not link.closed:
            return link
        daemon = self.daemons[node]
        if not daemon.reachable:
            raise ConnectionRefusedError(111, "Connection refused")
        link = self.links[node] = FakeLink(daemon)
        return link


class FakeSegments:
    """segments.Segments of the manager's own host, in a FakeDaemon's /dev/shm (that host's
    daemon sees the same segments)."""

    def __init__(self, prefix: str, shm: dict[str, Seg]) -> None:
        self.prefix = prefix
        self.shm = shm
        self._rings: dict[int, list[Seg]] = {}
        self._generation: dict[int, int] = {}

    def has(self, topic_id: int) -> bool:
        return topic_id in self._rings

    def topic_ids(self) -> list[int]:
        return list(self._rings)

    def current(self, topic_id: int) -> str:
        return self._rings[topic_id][-1].name

    def _new(self, topic_id: int, slots: int) -> Seg:
        generation = self._generation.get(topic_id, 0) + 1
        self._generation[topic_id] = generation
        seg = Seg(f"/ln.{self.prefix}.{topic_id}.{generation}", slots)
        self.shm[seg.name] = seg
        return seg

    def create(self, topic_id: int, topic: str, md_name: str, layout_hash: int,
               message_size: int, slots: int) -> str:
        self._rings[topic_id] = [self._new(topic_id, slots)]
        return self.current(topic_id)

    def grow(self, topic_id: int, md_name: str, layout_hash: int, message_size: int,
             slots: int) -> str:
        old = self._rings[topic_id][-1]
        new = self._new(topic_id, slots)
        new.seq, new.readers = old.seq, dict(old.readers)
        old.successor = new
        self._rings[topic_id].append(new)
        return new.name

    def reserve_reader(self, topic_id: int, index: int, pid: int, buffers: int) -> None:
        self._rings[topic_id][-1].readers[index] = (pid, buffers)

    def release_reader(self, topic_id: int, index: int) -> None:
        self._rings[topic_id][-1].readers.pop(index, None)

    def set_counts(self, topic_id: int, publishers: int, subscribers: int) -> None:
        self._rings[topic_id][-1].counts = (publishers, subscribers)

    def published(self, topic_id: int) -> int:
        return self._rings[topic_id][-1].newest().seq

    def remove(self, topic_id: int) -> list[str]:
        names = []
        for seg in self._rings.pop(topic_id, []):
            seg.linked = False
            self.shm.pop(seg.name, None)
            names.append(seg.name)
        return names

    def remove_all(self) -> int:
        return sum(len(self.remove(t)) for t in list(self._rings))


HOSTS = """hosts
a: eth0: 10.0.1.1
b: eth0: 10.0.1.2
c: eth0: 10.0.1.3
"""

GATEWAY = """network left
member_interfaces: a/eth0, c/eth0

network right
member_interfaces: c/eth0, b/eth0
"""


class World:
    """Hosts a, b, c with fake daemons, the manager's core and network; `local` names the
    host the manager runs on (its daemon reports the manager's own host id)."""

    def __init__(self, extra: str = "", local: str | None = None) -> None:
        self.instance = f"fake{next(_serial)}"
        text = (f"instance\nname: {self.instance}\nmanager: :54999\n\n{HOSTS}\n{extra}\n"
                "process p\nnode: a\ncommand: true\n")
        self.config = parse_text(text, "fake.lnc")
        local_id = _adminlib.host_id()
        self.daemons = {h: FakeDaemon(local_id if h == local else f"id-{h}") for h in "abc"}
        self.pool = FakePool(self.daemons, local)
        prefix = self.instance
        self.local_shm = self.daemons[local].shm if local else {}
        self.segments = FakeSegments(prefix, self.local_shm)
        self.core = Core(self.instance, Registry(lambda size, slots: size * slots),
                         self.segments, Services(),  # type: ignore[arg-type]
                         hosts=lambda core: Network(self.config, core, self.pool,
                                                    self.instance))  # type: ignore
        assert isinstance(self.core.hosts, Network)
        self.net = self.core.hosts
        self._request = itertools.count(1)
        self._pid = itertools.count(1000)

    async def up(self, *names: str) -> None:
        """One round of the host monitor (monitor.HostMonitor.run) for each host (all by
        default)."""
        for name in names or tuple(self.net.hosts):
            host = self.net.hosts[name]
            try:
                await self.net.monitor.check(host)
            except Exception as exc:
                await self.net.monitor.down(host, limits.reason(exc))

    def state(self, name: str) -> str:
        return self.net.hosts[name].state

    def client(self, host: str, name: str = "") -> Session:
        host_id = self.daemons[host].host_id
        session = Session(f"{host}:1")
        self.core.hello(session, p.Hello(p.MAGIC, p.VERSION, next(self._pid),
                                         name or f"{host}-client", "test", host_id))
        return session

    async def _port(self, session: Session, cls: type, topic: str, buffers: int,
                    flags: int) -> int:
        reply = await self.core.request(session, cls(next(self._request), topic, MD, HASH,
                                                     SIZE, buffers, flags))
        assert isinstance(reply, p.PortOk), reply
        return reply.port_id

    async def publish(self, session: Session, topic: str, buffers: int = 1) -> int:
        return await self._port(session, p.Publish, topic, buffers, 0)

    async def subscribe(self, session: Session, topic: str, buffers: int = 1,
                        flags: int = 0) -> int:
        return await self._port(session, p.Subscribe, topic, buffers, flags)

    async def close_port(self, session: Session, port_id: int) -> None:
        reply = await self.core.request(session, p.ClosePort(next(self._request), port_id))
        assert isinstance(reply, p.Ok), reply

    def topic_id(self, name: str) -> int:
        return self.core.registry.topics[name].id

    def ring_seg(self, host: str, topic: str) -> Seg:
        """The segment the manager uses for `topic` on `host` now."""
        tid = self.topic_id(topic)
        rings = self.net.clients.rings_of(host)
        assert rings is not None and rings.has(tid), f"no ring of {topic} on {host}"
        return self.daemons[host].shm[rings.current(tid)]

    def streams(self, topic: str) -> dict[tuple[str, str], Any]:
        tid = self.topic_id(topic)
        return {(s.src, s.dst): s for s in self.net.streams.values() if s.topic_id == tid}
