"""What the manager knows: connected clients, topics and their ports, and the checks a new
port must pass (docs/protocol.md, "Requests").  Pure logic without I/O: shared memory is
done by segments.py, which the caller drives with the plans this module makes.  Errors
carry the LN_E* table name ("ELIMIT"), not the number, so this module needs no libln."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum

from ...naming import MAX_NAME, client_name_problem, md_name_problem, topic_name_problem
from .defaults import RING_MEMORY_LIMIT, TOPIC_LIMIT

MAX_READERS = 64  # reader slots of a ring, hence subscribers of a topic

RingSize = Callable[[int, int], int]  # (message_size, slots) -> bytes of the segment


class RequestError(Exception):
    """A refused request: `code` is an LN_E* table name without the prefix ("ELIMIT")."""

    def __init__(self, code: str, text: str) -> None:
        super().__init__(text)
        self.code = code
        self.text = text


class PortKind(Enum):
    PUBLISHER = "publisher"
    SUBSCRIBER = "subscriber"


@dataclass(frozen=True)
class Limits:
    topics: int = TOPIC_LIMIT
    subscribers_per_topic: int = MAX_READERS
    message_size: int = 64 << 20
    buffers: int = 1024
    ring_memory: int = RING_MEMORY_LIMIT  # bytes of one topic's ring

    def __post_init__(self) -> None:
        if self.topics < 1:
            raise ValueError(f"topic limit must be at least 1, not {self.topics}")
        if not 1 <= self.subscribers_per_topic <= MAX_READERS:
            raise ValueError(f"subscribers per topic must be 1..{MAX_READERS}")
        if self.ring_memory < 1:
            raise ValueError(f"ring memory limit must be positive, not {self.ring_memory}")


@dataclass(eq=False)
class Client:
    id: int
    name: str
    pid: int
    address: str
    libln_version: str
    ports: dict[int, Port] = field(default_factory=dict)
    host_id: str = ""  # from HELLO: which host (hence which ln_daemon) the client runs on


@dataclass(eq=False)
class Topic:
    id: int
    name: str
    md_name: str  # of the port that created the topic
    layout_hash: int
    message_size: int
    slots: int
    ports: dict[int, Port] = field(default_factory=dict)
    readers: dict[int, int] = field(default_factory=dict)  # reader index -> port id
    # Adopted from a killed predecessor (docs/manager.md): kept without ports until the
    # adoption window closes, its old subscribers' reader slots held for them meanwhile.
    held: bool = False
    reserved: set[int] = field(default_factory=set)

    @property
    def publishers(self) -> int:
        return sum(p.kind is PortKind.PUBLISHER for p in self.ports.values())

    @property
    def subscribers(self) -> int:
        return len(self.ports) - self.publishers


@dataclass(eq=False)
class Port:
    id: int
    client: Client
    kind: PortKind
    topic: Topic
    md_name: str
    buffers: int
    flags: int
    reader_index: int | None  # subscribers only


@dataclass(frozen=True)
class PortRequest:
    kind: PortKind
    topic: str
    md_name: str
    layout_hash: int
    message_size: int
    buffers: int
    flags: int


@dataclass(frozen=True)
class PortPlan:
    """What registering a port takes, decided before anything changes.

    `topic` is None for a new topic, which gets id `topic_id` and a ring of `slots`;
    `grow_to` is the slot count of the next ring generation when the existing one is too
    small; `reader_index` is the reader slot a subscriber gets."""

    client: Client
    request: PortRequest
    topic: Topic | None
    topic_id: int
    slots: int
    grow_to: int | None
    reader_index: int | None
    reserve_reader: bool = True  # False: a returning subscriber's slot, still reserved


class Registry:
    """Clients, topics and ports of one manager instance."""

    def __init__(self, ring_size: RingSize, limits: Limits | None = None) -> None:
        self.limits = limits or Limits()
        self._ring_size = ring_size
        self.clients: dict[int, Client] = {}
        self.topics: dict[str, Topic] = {}
        self._next_client_id = 1
        self._next_port_id = 1
        self._next_topic_id = 1

    # ---- clients ------------------------------------------------------------------------
    def add_client(self, name: str, pid: int, address: str, libln_version: str,
                   host_id: str = "") -> Client:
        """Register a client under `name`, or `name-2`, `name-3`, ... if that is taken."""
        problem = client_name_problem(name)
        if problem:
            raise RequestError("EINVAL", problem)
        host_bytes = len(host_id.encode("utf-8"))
        if host_bytes > MAX_NAME:
            raise RequestError("EINVAL", f"host id of {host_bytes} bytes, at most {MAX_NAME}")
        taken = {c.name for c in self.clients.values()}
        unique, suffix = name, 2
        while unique in taken:
            unique, suffix = f"{name}-{suffix}", suffix + 1
        client = Client(self._next_client_id, unique, pid, address, libln_version,
                        host_id=host_id)
        self._next_client_id += 1
        self.clients[client.id] = client
        return client

    def remove_client(self, client: Client) -> None:
        """Forget a client; its ports must have been removed with remove_port first."""
        assert not client.ports, "remove the client's ports first"
        self.clients.pop(client.id, None)

    # ---- ports --------------------------------------------------------------------------
    def _check_request(self, request: PortRequest) -> None:
        limits = self.limits
        problem = topic_name_problem(request.topic) or md_name_problem(request.md_name)
        if problem:
            raise RequestError("EINVAL", problem)
        if not 1 <= request.message_size <= limits.message_size:
            raise RequestError("ELIMIT", f"topic {request.topic!r}: message size "
                               f"{request.message_size} out of range 1..{limits.message_size}")
        if not 1 <= request.buffers <= limits.buffers:
            raise RequestError("ELIMIT", f"topic {request.topic!r}: {request.buffers} buffers "
                               f"out of range 1..{limits.buffers}")

    def plan_port(self, client: Client, request: PortRequest) -> PortPlan:
        """Check a PUBLISH/SUBSCRIBE in the documented order; raises RequestError."""
        limits = self.limits
        self._check_request(request)
        topic = self.topics.get(request.topic)
        needed = max(request.buffers + 1, 2)
        if topic is not None:
            if (request.layout_hash, request.message_size) != (topic.layout_hash,
                                                               topic.message_size):
                raise RequestError("ELAYOUT", layout_mismatch(request, topic))
        elif len(self.topics) >= limits.topics:
            raise RequestError("ELIMIT", f"topic {request.topic!r}: the manager already has "
                               f"{len(self.topics)} topics, its limit is {limits.topics}")
        reader_index = None
        if request.kind is PortKind.SUBSCRIBER:
            readers = topic.readers if topic is not None else {}
            # slots held for subscribers that are expected back count as taken
            taken = set(readers) | (topic.reserved if topic is not None else set())
            if len(taken) >= limits.subscribers_per_topic:
                raise RequestError("ELIMIT", f"topic {request.topic!r} already has "
                                   f"{len(taken)} subscribers, the limit is "
                                   f"{limits.subscribers_per_topic}")
            reader_index = min(set(range(MAX_READERS)) - taken)
        if topic is None:
            self._check_ring(request, needed)
            return PortPlan(client, request, None, self._next_topic_id, needed, None,
                            reader_index)
        grow_to = None
        if needed > topic.slots:
            # Doubling keeps a series of ever deeper subscribers from making a generation
            # each; it never goes past the deepest ring a port can ask for.
            grow_to = min(max(needed, 2 * topic.slots), limits.buffers + 1)
            if self.ring_bytes(request.message_size, grow_to) > limits.ring_memory:
                grow_to = needed
            self._check_ring(request, grow_to)
        return PortPlan(client, request, topic, topic.id, topic.slots, grow_to, reader_index)

    def plan_reclaim(self, client: Client, request: PortRequest, topic_id: int,
                     reader_index: int | None) -> PortPlan:
        """Check a RECLAIM_PORT: a port a reconnecting client holds on a ring of topic
        `topic_id` (the caller checked that the segment it names is one of that topic's),
        with its reader slot for a subscriber.  RequestError if anything does not fit."""
        self._check_request(request)
        topic = self.topics.get(request.topic)
        if topic is None or topic.id != topic_id:
            raise RequestError("ENOTFOUND", f"topic {request.topic!r} has no ring {topic_id} "
                               "here (it was removed, or its segment never held that topic)")
        if (request.layout_hash, request.message_size) != (topic.layout_hash,
                                                           topic.message_size):
            raise RequestError("ELAYOUT", layout_mismatch(request, topic))
        if request.buffers + 1 > topic.slots:
            raise RequestError("EINVAL", f"topic {request.topic!r}: {request.buffers} buffers "
                               f"do not fit its ring of {topic.slots} slots")
        if request.kind is PortKind.PUBLISHER:
            if reader_index is not None:
                raise RequestError("EINVAL", f"topic {request.topic!r}: a publisher holds no "
                                   f"reader slot, not {reader_index}")
            return PortPlan(client, request, topic, topic.id, topic.slots, None, None, False)
        if reader_index is None or not 0 <= reader_index < MAX_READERS:
            raise RequestError("EINVAL", f"topic {request.topic!r}: reader slot "
                               f"{reader_index} out of range 0..{MAX_READERS - 1}")
        if reader_index in topic.readers:
            raise RequestError("EBUSY", f"topic {request.topic!r}: reader slot {reader_index} "
                               "belongs to another subscriber")
        reserved = reader_index in topic.reserved
        if not reserved and len(topic.readers) + len(topic.reserved) \
                >= self.limits.subscribers_per_topic:
            raise RequestError("ELIMIT", f"topic {request.topic!r} already has "
                               f"{len(topic.readers) + len(topic.reserved)} subscribers, the "
                               f"limit is {self.limits.subscribers_per_topic}")
        return PortPlan(client, request, topic, topic.id, topic.slots, None, reader_index,
                        not reserved)

    def adopt_topic(self, topic_id: int, name: str, md_name: str, layout_hash: int,
                    message_size: int, slots: int, readers: set[int]) -> Topic:
        """Register a topic whose ring a killed predecessor left: held without ports until
        release_hold, with `readers` (the slots in use in its ring) kept for their
        subscribers.  Later topics get higher ids."""
        problem = topic_name_problem(name) or md_name_problem(md_name)
        if problem:
            raise RequestError("EINVAL", problem)
        if name in self.topics:
            raise RequestError("EEXIST", f"topic {name!r} is already registered")
        topic = Topic(topic_id, name, md_name, layout_hash, message_size, slots, held=True,
                      reserved=set(readers))
        self.topics[name] = topic
        self._next_topic_id = max(self._next_topic_id, topic_id + 1)
        return topic

    def release_hold(self, topic: Topic) -> list[int]:
        """End an adopted topic's hold: the reader slots nobody came back for (to be freed in
        its ring).  The topic goes with drop_topic_if_unused if nobody took it."""
        topic.held = False
        unclaimed = sorted(topic.reserved)
        topic.reserved.clear()
        return unclaimed

    def add_topic(self, plan: PortPlan) -> Topic:
        """Register the new topic of `plan` (after its ring exists), still without ports."""
        assert plan.topic is None and plan.topic_id == self._next_topic_id
        request = plan.request
        topic = Topic(plan.topic_id, request.topic, request.md_name, request.layout_hash,
                      request.message_size, plan.slots)
        self._next_topic_id += 1
        self.topics[topic.name] = topic
        return topic

    def grow_topic(self, topic: Topic, slots: int) -> None:
        """Record that the topic's ring was replaced by one with `slots` slots."""
        assert slots > topic.slots
        topic.slots = slots

    def add_port(self, plan: PortPlan, topic: Topic) -> Port:
        """Register the port of `plan` on `topic` (which now has a big enough ring)."""
        request = plan.request
        port = Port(self._next_port_id, plan.client, request.kind, topic, request.md_name,
                    request.buffers, request.flags, plan.reader_index)
        self._next_port_id += 1
        topic.ports[port.id] = port
        if port.reader_index is not None:
            assert port.reader_index not in topic.readers
            topic.readers[port.reader_index] = port.id
            topic.reserved.discard(port.reader_index)
        plan.client.ports[port.id] = port
        return port

    def find_port(self, client: Client, port_id: int) -> Port:
        port = client.ports.get(port_id)
        if port is None:
            raise RequestError("ENOTFOUND", f"client {client.name!r} has no port {port_id}")
        return port

    def remove_port(self, port: Port) -> bool:
        """Forget a port; True if its topic has no ports left and was removed too."""
        topic = port.topic
        port.client.ports.pop(port.id, None)
        topic.ports.pop(port.id, None)
        if port.reader_index is not None:
            topic.readers.pop(port.reader_index, None)
        return self.drop_topic_if_unused(topic)

    def drop_topic_if_unused(self, topic: Topic) -> bool:
        """Remove a topic without ports (also one whose first port failed); True if removed."""
        if topic.ports or topic.held or self.topics.get(topic.name) is not topic:
            return False
        del self.topics[topic.name]
        return True

    def topic(self, name: str) -> Topic:
        topic = self.topics.get(name)
        if topic is None:
            raise RequestError("ENOTFOUND", f"no topic {name!r}")
        return topic

    # ---- internals ----------------------------------------------------------------------
    def ring_bytes(self, message_size: int, slots: int) -> int:
        return self._ring_size(message_size, slots)

    def _check_ring(self, request: PortRequest, slots: int) -> None:
        size = self.ring_bytes(request.message_size, slots)
        if size == 0 or size > self.limits.ring_memory:
            raise RequestError("ELIMIT", f"topic {request.topic!r}: a ring of {slots} slots "
                               f"of {request.message_size} bytes takes {size} bytes, the "
                               f"limit per topic is {self.limits.ring_memory}")


def layout_mismatch(request: PortRequest, topic: Topic) -> str:
    """The LN_ELAYOUT text: both md names, hashes and sizes."""
    return (f"topic '{request.topic}': layout of md '{request.md_name}' "
            f"(hash 0x{request.layout_hash:016x}, {request.message_size} bytes) differs from "
            f"the topic's md '{topic.md_name}' (hash 0x{topic.layout_hash:016x}, "
            f"{topic.message_size} bytes)")
