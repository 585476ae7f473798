"""One host's topic rings as the manager's core drives them, behind one async interface:
LocalRings does it with libln on the manager's own host (segments.py), RemoteRings asks
that host's ln_daemon.  A remote host whose daemon is away keeps its bookkeeping; what
could not be done there is done when the daemon is back (resync)."""

from __future__ import annotations

import asyncio
import logging
from dataclasses import dataclass, field
from typing import Any, Protocol

from ...naming import segment_name
from .model import RequestError
from .segments import RETIRE_TIMEOUT, Segments

log = logging.getLogger("ln_manager")


class Rings(Protocol):
    """What core.py needs of one host's rings (topic ids as in the registry)."""

    host: str

    def has(self, topic_id: int) -> bool: ...
    def current(self, topic_id: int) -> str: ...
    def topic_ids(self) -> list[int]: ...
    async def create(self, topic_id: int, topic: str, md_name: str, layout_hash: int,
                     message_size: int, slots: int) -> str: ...
    async def grow(self, topic_id: int, md_name: str, layout_hash: int, message_size: int,
                   slots: int) -> str: ...
    async def reserve_reader(self, topic_id: int, index: int, pid: int,
                             buffers: int) -> None: ...
    async def release_reader(self, topic_id: int, index: int) -> None: ...
    async def set_counts(self, topic_id: int, publishers: int, subscribers: int) -> None: ...
    async def remove(self, topic_id: int) -> list[str]: ...


class LocalRings:
    """The manager's own host: segments.Segments, synchronously."""

    def __init__(self, segments: Segments, host: str = "") -> None:
        self.segments = segments
        self.host = host

    def has(self, topic_id: int) -> bool:
        return self.segments.has(topic_id)

    def current(self, topic_id: int) -> str:
        return self.segments.current(topic_id)

    def topic_ids(self) -> list[int]:
        return self.segments.topic_ids()

    async def create(self, topic_id: int, topic: str, md_name: str, layout_hash: int,
                     message_size: int, slots: int) -> str:
        return self.segments.create(topic_id, topic, md_name, layout_hash, message_size,
                                    slots)

    async def grow(self, topic_id: int, md_name: str, layout_hash: int, message_size: int,
                   slots: int) -> str:
        return self.segments.grow(topic_id, md_name, layout_hash, message_size, slots)

    async def reserve_reader(self, topic_id: int, index: int, pid: int, buffers: int) -> None:
        self.segments.reserve_reader(topic_id, index, pid, buffers)

    async def release_reader(self, topic_id: int, index: int) -> None:
        self.segments.release_reader(topic_id, index)

    async def set_counts(self, topic_id: int, publishers: int, subscribers: int) -> None:
        self.segments.set_counts(topic_id, publishers, subscribers)

    async def remove(self, topic_id: int) -> list[str]:
        return self.segments.remove(topic_id)


class DaemonLink(Protocol):
    """The part of daemon_client.DaemonClient that rings need."""

    async def ring_create(self, name: str, topic: str, md_name: str, layout_hash: int,
                          message_size: int, slots: int, *, adopt: bool = False) -> None: ...
    async def ring_retire(self, old: str, successor: str, timeout: float = 1.0) -> None: ...
    async def ring_reserve_reader(self, name: str, index: int, pid: int,
                                  buffers: int) -> None: ...
    async def ring_release_reader(self, name: str, index: int) -> None: ...
    async def ring_set_counts(self, name: str, publishers: int, subscribers: int) -> None: ...
    async def ring_remove(self, name: str) -> None: ...


@dataclass
class _Remote:
    topic: str
    md_name: str
    layout_hash: int
    message_size: int
    slots: int
    names: list[str] = field(default_factory=list)
    readers: dict[int, tuple[int, int]] = field(default_factory=dict)  # index -> pid, buffers
    counts: tuple[int, int] = (0, 0)
    released: set[int] = field(default_factory=set)  # reader slots freed while unreachable


class RemoteRings:
    """Rings on another host, made by its ln_daemon.  Segment names carry the host's tag
    (`/ln.<instance>.<topic>.<generation>.<tag>`) so that hosts sharing one /dev/shm (one
    machine with several host ids) never collide."""

    def __init__(self, host: str, prefix: str, tag: str) -> None:
        self.host = host
        self.prefix = prefix  # sanitized instance
        self.tag = tag
        self.link: DaemonLink | None = None  # None while the daemon is unreachable
        self.down_reason = "not connected yet"
        self._rings: dict[int, _Remote] = {}
        # Last generation used per topic, kept when a ring is removed: a ring made again
        # while the topic lives gets a new name, never that of a segment a stream of the
        # daemon may still map (or that an unreachable daemon could not remove).
        self._generations: dict[int, int] = {}
        self._unremoved: list[str] = []  # segments removed while the daemon was unreachable

    def has(self, topic_id: int) -> bool:
        return topic_id in self._rings

    def current(self, topic_id: int) -> str:
        return self._rings[topic_id].names[-1]

    def topic_ids(self) -> list[int]:
        return list(self._rings)

    def _next_name(self, topic_id: int) -> str:
        generation = self._generations.get(topic_id, 0) + 1
        self._generations[topic_id] = generation
        return segment_name(self.prefix, topic_id, generation, self.tag)

    def _need_link(self, what: str) -> DaemonLink:
        if self.link is None:
            raise RequestError("ECONNECTION", f"{what}: the ln_daemon of host {self.host!r} "
                               f"is unreachable ({self.down_reason})")
        return self.link

    async def _do(self, what: str, call: Any) -> None:
        try:
            await call
        except Exception as exc:  # DaemonError, ConnectionError: the text is what matters
            raise RequestError("ESYS", f"{what} on host {self.host!r}: {exc}") from None

    async def create(self, topic_id: int, topic: str, md_name: str, layout_hash: int,
                     message_size: int, slots: int) -> str:
        assert topic_id not in self._rings
        link = self._need_link(f"topic {topic!r}")
        name = self._next_name(topic_id)
        await self._do(f"topic {topic!r}: creating segment {name}",
                       link.ring_create(name, topic, md_name, layout_hash, message_size,
                                        slots))
        self._rings[topic_id] = _Remote(topic, md_name, layout_hash, message_size, slots,
                                        [name])
        return name

    async def grow(self, topic_id: int, md_name: str, layout_hash: int, message_size: int,
                   slots: int) -> str:
        ring = self._rings[topic_id]
        link = self._need_link(f"topic {ring.topic!r}")
        name = self._next_name(topic_id)
        await self._do(f"topic {ring.topic!r}: creating segment {name}",
                       link.ring_create(name, ring.topic, md_name, layout_hash, message_size,
                                        slots))
        try:
            await self._do(f"topic {ring.topic!r}: retiring {ring.names[-1]} into {name}",
                           link.ring_retire(ring.names[-1], name, RETIRE_TIMEOUT))
        except RequestError:
            await self._quietly(link.ring_remove(name))
            raise
        ring.names.append(name)
        ring.slots = slots
        return name

    async def reserve_reader(self, topic_id: int, index: int, pid: int, buffers: int) -> None:
        ring = self._rings[topic_id]
        link = self._need_link(f"topic {ring.topic!r}")
        await self._do(f"topic {ring.topic!r}: reserving reader slot {index}",
                       link.ring_reserve_reader(ring.names[-1], index, pid, buffers))
        ring.readers[index] = (pid, buffers)
        ring.released.discard(index)

    async def release_reader(self, topic_id: int, index: int) -> None:
        ring = self._rings[topic_id]
        ring.readers.pop(index, None)
        if self.link is not None:
            await self._quietly(self.link.ring_release_reader(ring.names[-1], index))
        else:  # the slot would hold back the host's publishers: freed in resync()
            ring.released.add(index)

    async def set_counts(self, topic_id: int, publishers: int, subscribers: int) -> None:
        ring = self._rings[topic_id]
        ring.counts = (publishers, subscribers)
        if self.link is not None:
            await self._quietly(self.link.ring_set_counts(ring.names[-1], publishers,
                                                          subscribers))

    async def remove(self, topic_id: int) -> list[str]:
        ring = self._rings.pop(topic_id, None)
        if ring is None:
            return []
        if self.link is not None:
            for name in ring.names:
                try:
                    await self.link.ring_remove(name)
                except ConnectionError as exc:
                    # the daemon died and the link is not marked down yet: the segment
                    # stays in its host's /dev/shm, so remove it when the daemon is back
                    log.warning("host %r: %s; %s is removed when its daemon is back",
                                self.host, exc, name)
                    self._unremoved.append(name)
                except Exception as exc:
                    log.warning("host %r: %s", self.host, exc)
        else:
            log.warning("host %r unreachable: its segments %s are removed when its daemon "
                        "is back", self.host, ", ".join(ring.names))
            self._unremoved += ring.names
        return ring.names

    async def resync(self, timeout: float) -> None:
        """After the daemon (re)connected: remove the segments and free the reader slots
        that could not be removed and freed while it was unreachable, adopt every ring this
        manager has there (they survive a daemon restart in /dev/shm) and set the counts.
        The caller keeps other ring operations out meanwhile, so every call is bounded by
        `timeout`: a daemon that does not answer (or goes) ends it with TimeoutError (or
        ConnectionError); what is left is done on the next resync."""
        link = self._need_link("resync")
        while self._unremoved:
            try:
                await asyncio.wait_for(link.ring_remove(self._unremoved[0]), timeout)
            except (TimeoutError, ConnectionError):
                raise
            except Exception as exc:
                log.warning("host %r: %s", self.host, exc)
            del self._unremoved[0]
        for ring in list(self._rings.values()):
            name = ring.names[-1]
            try:
                await asyncio.wait_for(
                    link.ring_create(name, ring.topic, ring.md_name, ring.layout_hash,
                                     ring.message_size, ring.slots, adopt=True), timeout)
                await asyncio.wait_for(link.ring_set_counts(name, *ring.counts), timeout)
                for index in sorted(ring.released):
                    await asyncio.wait_for(link.ring_release_reader(name, index), timeout)
                ring.released.clear()
            except (TimeoutError, ConnectionError):
                raise
            except Exception as exc:
                log.warning("host %r: re-adopting %s of topic %r failed: %s", self.host, name,
                            ring.topic, exc)

    def forget_all(self) -> None:
        self._rings.clear()

    async def _quietly(self, call: Any) -> None:
        try:
            await call
        except Exception as exc:
            log.warning("host %r: %s", self.host, exc)
