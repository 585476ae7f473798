"""Shared-memory segments of topics, through ln_ring_admin_* (_adminlib, libln_admin.so): naming,
creating, growing into a next generation, reader slots, counts and unlinking, and adopting
the rings a killed predecessor left.  The manager maps only segment headers; clients map
the data.  Which ring a topic needs is decided by registry.py; this module only carries it
out."""

from __future__ import annotations

import ctypes
import logging
import os
from dataclasses import dataclass, field
from pathlib import Path

from ... import _adminlib
from ..._adminlib import last_error
from ...errors import LnError
from ...naming import parse_segment_name, sanitize_instance, segment_name, segment_prefix
from .model import RequestError, md_name_problem, topic_name_problem

log = logging.getLogger("ln_manager")

RETIRE_TIMEOUT = 1.0  # seconds ln_ring_admin_retire may wait for a publisher's loan
SHM_DIR = Path("/dev/shm")


@dataclass(frozen=True)
class AdoptedRing:
    """A topic's ring as a predecessor left it: every generation, the newest one's header."""

    topic_id: int
    topic: str
    md_name: str
    layout_hash: int
    message_size: int
    slots: int
    names: tuple[str, ...]  # oldest first
    readers: frozenset[int]  # reader slots in use
    write_seq: int


def ring_segment_size(message_size: int, slots: int) -> int:
    """Bytes of a ring segment, as libln lays it out."""
    return int(_adminlib.ln_ring_segment_size(message_size, slots))


def _failure(what: str, exc: LnError) -> RequestError:
    """The refusal for a failed admin call, with libln's own account of it (errno etc.)."""
    detail = last_error()
    return RequestError(exc.name or "ESYS", f"{what}: {exc.name}: {detail or exc.text}")


@dataclass
class _TopicRings:
    topic: str
    names: list[str] = field(default_factory=list)  # every generation, oldest first
    admin: object | None = None  # header mapping of the newest generation

    @property
    def current(self) -> str:
        return self.names[-1]


class Segments:
    """The rings of every topic of one instance, keyed by topic id."""

    def __init__(self, instance: str) -> None:
        self.prefix = sanitize_instance(instance)
        self._rings: dict[int, _TopicRings] = {}
        # Last generation used per topic, kept when a topic's ring is removed: a ring made
        # again on this host while the topic lives gets a new name, so that nothing that
        # still maps the removed segment (a daemon's stream) is taken for it.
        self._generations: dict[int, int] = {}

    def purge(self) -> int:
        """Unlink every segment of this instance left by an earlier manager; how many."""
        try:
            return int(_adminlib.ln_ring_admin_purge_instance(self.prefix.encode()))
        except LnError as exc:
            raise _failure(f"removing stale segments {segment_prefix(self.prefix)}*", exc) from None

    def adopt(self) -> tuple[list[AdoptedRing], list[tuple[str, str]]]:
        """Take over the rings of this instance that a killed predecessor left in /dev/shm
        (`/ln.<instance>.<topic id>.<generation>`): the adopted ones, and the segments that
        were unlinked instead, each with the reason (not a ring of ours, an inconsistent
        chain of generations, a second ring of one topic)."""
        chains: dict[int, dict[int, str]] = {}
        removed: list[tuple[str, str]] = []
        try:
            entries = sorted(os.listdir(SHM_DIR))
        except OSError as exc:
            raise RequestError("ESYS", f"cannot list {SHM_DIR}: {exc.strerror}") from None
        for entry in entries:
            if not entry.startswith(segment_prefix(self.prefix)[1:]):
                continue
            match = parse_segment_name(self.prefix, entry)
            if match is None:
                removed.append((self._drop(f"/{entry}"), "not named like a ring of this host"))
                continue
            chains.setdefault(match[0], {})[match[1]] = f"/{entry}"
        adopted: dict[str, AdoptedRing] = {}
        for topic_id, generations in sorted(chains.items()):
            names = [generations[g] for g in sorted(generations)]
            try:
                ring, admin = self._adopt_chain(topic_id, names)
            except RequestError as exc:
                removed += [(self._drop(name), exc.text) for name in names]
                continue
            older = adopted.get(ring.topic)
            if older is not None:  # one topic, two ids: the newer id wins
                removed += [(self._drop(name), f"topic {ring.topic!r} has a newer ring")
                            for name in older.names]
                old = self._rings.pop(older.topic_id)
                _adminlib.ln_ring_admin_close(old.admin)
            adopted[ring.topic] = ring
            self._rings[topic_id] = _TopicRings(ring.topic, list(names), admin)
            self._generations[topic_id] = max(generations)
        return list(adopted.values()), removed

    def _adopt_chain(self, topic_id: int, names: list[str]) -> tuple[AdoptedRing, object]:
        """Open every generation of one topic and check that they form one chain: the same
        topic and layout, every one but the newest retired.  The newest one's admin handle
        stays open (the caller owns it)."""
        infos: list[_adminlib.RingInfo] = []
        admin: object | None = None
        try:
            for name in names:
                handle = _adminlib.RingAdminHandle()
                try:
                    _adminlib.ln_ring_admin_open(ctypes.byref(handle), name.encode())
                except LnError as exc:
                    raise _failure(f"segment {name}", exc) from None
                info = _adminlib.RingInfo()
                _adminlib.ln_ring_admin_info(handle, ctypes.byref(info))
                infos.append(info)
                if admin is not None:
                    _adminlib.ln_ring_admin_close(admin)
                admin = handle
            newest = infos[-1]
            topic = newest.topic.decode("utf-8", "replace")
            md_name = newest.md_name.decode("utf-8", "replace")
            problem = topic_name_problem(topic) or md_name_problem(md_name)
            if problem:
                raise RequestError("EPROTOCOL", f"header of {names[-1]}: {problem}")
            for name, info in zip(names, infos, strict=True):
                if (info.topic, info.layout_hash, info.message_size) != \
                        (newest.topic, newest.layout_hash, newest.message_size):
                    raise RequestError("EPROTOCOL", f"{name} holds another topic or layout "
                                       f"than {names[-1]}")
                if bool(info.retired) != (info is not newest):
                    raise RequestError("EPROTOCOL", f"{name} is {'' if info.retired else 'not '}"
                                       "retired, unlike the newest generation of a topic")
            readers = frozenset(i for i in range(64) if newest.active_readers >> i & 1)
            ring = AdoptedRing(topic_id, topic, md_name, newest.layout_hash,
                               newest.message_size, newest.slot_count, tuple(names), readers,
                               newest.write_seq)
        except RequestError:
            if admin is not None:
                _adminlib.ln_ring_admin_close(admin)
            raise
        return ring, admin

    def _drop(self, name: str) -> str:
        self._unlink(name)
        return name

    def topic_of(self, name: str) -> int | None:
        """The topic id of a segment named by this manager's scheme (any generation), or
        None if `name` is not one."""
        if not name.startswith("/"):
            return None
        match = parse_segment_name(self.prefix, name)
        return match[0] if match else None

    def has(self, topic_id: int) -> bool:
        return topic_id in self._rings

    def topic_ids(self) -> list[int]:
        return list(self._rings)

    def current(self, topic_id: int) -> str:
        return self._rings[topic_id].current

    def names(self, topic_id: int) -> list[str]:
        return list(self._rings[topic_id].names)

    def create(self, topic_id: int, topic: str, md_name: str, layout_hash: int,
               message_size: int, slots: int) -> str:
        """Create the first generation of a topic's ring on this host (1, unless the topic
        had a ring here before); returns its name."""
        assert topic_id not in self._rings
        rings = _TopicRings(topic)
        generation = self._generations.get(topic_id, 0) + 1
        rings.admin = self._create(rings, topic_id, generation, md_name, layout_hash,
                                   message_size, slots)
        self._generations[topic_id] = generation
        rings.names.append(segment_name(self.prefix, topic_id, generation))
        self._rings[topic_id] = rings
        return rings.current

    def grow(self, topic_id: int, md_name: str, layout_hash: int, message_size: int,
             slots: int) -> str:
        """Replace a topic's ring by a next generation of `slots` slots and retire the old
        one into it; the old segment stays linked until the topic is removed."""
        rings = self._rings[topic_id]
        generation = self._generations[topic_id] + 1
        successor = self._create(rings, topic_id, generation, md_name, layout_hash,
                                 message_size, slots)
        self._generations[topic_id] = generation
        name = segment_name(self.prefix, topic_id, generation)
        try:
            _adminlib.ln_ring_admin_retire(rings.admin, successor, name.encode(), RETIRE_TIMEOUT)
        except LnError as exc:
            _adminlib.ln_ring_admin_close(successor)
            self._unlink(name)
            raise _failure(f"topic {rings.topic!r}: retiring {rings.current} into {name}",
                           exc) from None
        _adminlib.ln_ring_admin_close(rings.admin)
        rings.admin = successor
        rings.names.append(name)
        return name

    def reserve_reader(self, topic_id: int, index: int, pid: int, buffers: int) -> None:
        rings = self._rings[topic_id]
        try:
            _adminlib.ln_ring_admin_reserve_reader(rings.admin, index, pid, buffers)
        except LnError as exc:
            raise _failure(f"topic {rings.topic!r}: reserving reader slot {index} in "
                           f"{rings.current}", exc) from None

    def release_reader(self, topic_id: int, index: int) -> None:
        rings = self._rings[topic_id]
        try:
            _adminlib.ln_ring_admin_release_reader(rings.admin, index)
        except LnError as exc:
            log.warning("topic %r: releasing reader slot %d of %s failed: %s", rings.topic,
                        index, rings.current, exc)

    def set_counts(self, topic_id: int, publishers: int, subscribers: int) -> None:
        rings = self._rings[topic_id]
        try:
            _adminlib.ln_ring_admin_set_counts(rings.admin, publishers, subscribers)
        except LnError as exc:
            raise _failure(f"topic {rings.topic!r}: setting port counts in {rings.current}",
                           exc) from None

    def published(self, topic_id: int) -> int:
        """How many samples the topic has had (its newest sequence number)."""
        rings = self._rings[topic_id]
        seq = ctypes.c_uint64(0)
        try:
            _adminlib.ln_ring_admin_write_seq(rings.admin, ctypes.byref(seq))
        except LnError as exc:
            raise _failure(f"topic {rings.topic!r}: reading its sequence number", exc) from None
        return int(seq.value)

    def remove(self, topic_id: int) -> list[str]:
        """Unmap and unlink every generation of a topic's ring; the names unlinked."""
        rings = self._rings.pop(topic_id, None)
        if rings is None:
            return []
        if rings.admin is not None:
            _adminlib.ln_ring_admin_close(rings.admin)
            rings.admin = None
        for name in rings.names:
            self._unlink(name)
        return rings.names

    def remove_all(self) -> int:
        """Remove the rings of every topic (manager shutdown); how many segments."""
        return sum(len(self.remove(topic_id)) for topic_id in list(self._rings))

    def _create(self, rings: _TopicRings, topic_id: int, generation: int, md_name: str,
                layout_hash: int, message_size: int, slots: int) -> object:
        name = segment_name(self.prefix, topic_id, generation)
        handle = _adminlib.RingAdminHandle()
        try:
            _adminlib.ln_ring_admin_create(ctypes.byref(handle), name.encode(),
                                           rings.topic.encode(), md_name.encode(), layout_hash,
                                           message_size, slots)
        except LnError as exc:
            raise _failure(f"topic {rings.topic!r}: creating segment {name} with {slots} "
                           f"slots of {message_size} bytes", exc) from None
        return handle

    @staticmethod
    def _unlink(name: str) -> None:
        try:
            _adminlib.ln_ring_admin_unlink(name.encode())
        except LnError as exc:
            log.warning("unlinking segment %s failed: %s", name, exc)
