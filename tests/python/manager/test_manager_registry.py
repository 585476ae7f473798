"""The registry's decisions without sockets or shared memory: client names, the checks of
a new port in the documented order, reader slots, ring sizing and growth, topic removal.
The ring size function is a stand-in formula; the real one is libln's."""

from __future__ import annotations

from typing import Any

import pytest

from links_and_nodes.manager.registry.model import (
    Limits,
    Port,
    PortKind,
    PortRequest,
    Registry,
    RequestError,
    md_name_problem,
    topic_name_problem,
)

MIB = 1 << 20
PUB, SUB = PortKind.PUBLISHER, PortKind.SUBSCRIBER
HASH = 0x1F2E3D4C5B6A7988


def ring_size(message_size: int, slots: int) -> int:
    return 4096 + slots * (message_size + 64)


def request(kind: PortKind = PUB, topic: str = "robot.state", md: str = "robot/joint_state",
            layout_hash: int = HASH, size: int = 184, buffers: int = 1) -> PortRequest:
    return PortRequest(kind, topic, md, layout_hash, size, buffers, 0)


class World:
    """A registry with a client, and `open` doing what core.Core does with a plan."""

    def __init__(self, **limits: int) -> None:
        self.registry = Registry(ring_size, Limits(**limits))
        self.client = self.registry.add_client("ctl", 100, "127.0.0.1:1", "0.1.0")
        self.grown: list[int] = []

    def open(self, req: PortRequest | None = None, **kwargs: Any) -> Port:
        req = req or request(**kwargs)
        plan = self.registry.plan_port(self.client, req)
        topic = plan.topic
        if topic is None:
            topic = self.registry.add_topic(plan)
        elif plan.grow_to is not None:
            self.grown.append(plan.grow_to)
            self.registry.grow_topic(topic, plan.grow_to)
        return self.registry.add_port(plan, topic)

    def refused(self, code: str, **kwargs: Any) -> str:
        with pytest.raises(RequestError) as info:
            self.registry.plan_port(self.client, request(**kwargs))
        assert info.value.code == code, info.value.text
        return info.value.text


def test_client_names_get_suffixes() -> None:
    registry = Registry(ring_size)
    names = [registry.add_client("ctl", 1, "a", "v").name for _ in range(3)]
    assert names == ["ctl", "ctl-2", "ctl-3"]
    second = next(c for c in registry.clients.values() if c.name == "ctl-2")
    registry.remove_client(second)
    assert registry.add_client("ctl", 1, "a", "v").name == "ctl-2"
    assert registry.add_client("ctl-2", 1, "a", "v").name == "ctl-2-2"


def test_client_keeps_its_host_id() -> None:
    registry = Registry(ring_size)
    assert registry.add_client("a", 1, "x", "v").host_id == ""
    assert registry.add_client("b", 1, "x", "v", "rack-ä/42").host_id == "rack-ä/42"
    assert registry.add_client("c", 1, "x", "v", "h" * 255).host_id == "h" * 255
    with pytest.raises(RequestError) as info:
        registry.add_client("d", 1, "x", "v", "ä" * 128)
    assert (info.value.code, info.value.text) == ("EINVAL", "host id of 256 bytes, at most 255")


def test_ports_keep_their_flags() -> None:
    world = World()
    publisher = world.open(PortRequest(PUB, "t.flags", "m/d", HASH, 8, 1, 0x1))
    tcp = world.open(PortRequest(SUB, "t.flags", "m/d", HASH, 8, 1, 0x200))
    udp = world.open(PortRequest(SUB, "t.flags", "m/d", HASH, 8, 4, 0x100))
    assert (publisher.flags, tcp.flags, udp.flags) == (0x1, 0x200, 0x100)
    assert world.registry.topics["t.flags"].ports[tcp.id].flags == 0x200


@pytest.mark.parametrize("name", ["", "a\nb", "x" * 256, "tab\there"])
def test_bad_client_names(name: str) -> None:
    with pytest.raises(RequestError) as info:
        Registry(ring_size).add_client(name, 1, "a", "v")
    assert info.value.code == "EINVAL"


@pytest.mark.parametrize("name, ok", [
    ("robot.state", True), ("a", True), ("A-z_0.9:x/y", True), ("t" * 255, True),
    ("", False), ("t" * 256, False), (".hidden", False), ("sp ace", False),
    ("umlaut.ä", False), ("nul\0", False), ("star*", False),
])
def test_topic_names(name: str, ok: bool) -> None:
    assert (topic_name_problem(name) is None) == ok


@pytest.mark.parametrize("name, ok", [
    ("robot/joint_state", True), ("x", True), ("_a/b1/C_2", True), ("m" * 255, True),
    ("", False), ("m" * 256, False), ("robot//x", False), ("/robot", False),
    ("robot/", False), ("robot/1st", False), ("robot/../x", False), ("robot.state", False),
])
def test_md_names(name: str, ok: bool) -> None:
    assert (md_name_problem(name) is None) == ok


def test_checks_come_in_the_documented_order() -> None:
    world = World(topics=1)
    world.open()
    # every check fails for this request; the first one in the table wins
    assert world.refused("EINVAL", topic=".bad", md="1bad", size=0, buffers=0,
                         layout_hash=1)
    assert world.refused("EINVAL", md="1bad", size=0, buffers=0, layout_hash=1)
    assert "message size 0" in world.refused("ELIMIT", size=0, buffers=0, layout_hash=1)
    assert "0 buffers" in world.refused("ELIMIT", buffers=0, layout_hash=1)
    world.refused("ELAYOUT", layout_hash=1)
    assert "limit is 1" in world.refused("ELIMIT", topic="other")


@pytest.mark.parametrize("size, ok", [(1, True), (64 * MIB, True), (0, False),
                                      (64 * MIB + 1, False)])
def test_message_size_limit(size: int, ok: bool) -> None:
    world = World(ring_memory=1 << 40)
    if ok:
        world.open(size=size)
    else:
        assert f"message size {size} out of range 1..{64 * MIB}" in world.refused(
            "ELIMIT", size=size)


@pytest.mark.parametrize("buffers, ok", [(1, True), (1024, True), (0, False), (1025, False)])
def test_buffer_limit(buffers: int, ok: bool) -> None:
    world = World()
    if ok:
        assert world.open(kind=SUB, buffers=buffers).topic.slots == buffers + 1
    else:
        assert f"{buffers} buffers out of range 1..1024" in world.refused("ELIMIT",
                                                                           buffers=buffers)


def test_layout_mismatch_names_both_sides() -> None:
    world = World()
    world.open(md="robot/joint_state", layout_hash=0xABC, size=184)
    text = world.refused("ELAYOUT", md="robot/joint_state_v2", layout_hash=0xDEF, size=180)
    assert text == ("topic 'robot.state': layout of md 'robot/joint_state_v2' (hash "
                    "0x0000000000000def, 180 bytes) differs from the topic's md "
                    "'robot/joint_state' (hash 0x0000000000000abc, 184 bytes)")
    # same hash, other size: also a mismatch
    assert "(hash 0x0000000000000abc, 185 bytes)" in world.refused(
        "ELAYOUT", layout_hash=0xABC, size=185)
    # the md name alone does not matter: the layout does
    assert world.open(md="other/name", layout_hash=0xABC, size=184).md_name == "other/name"


def test_topic_limit() -> None:
    world = World(topics=3)
    ports = [world.open(topic=f"t{i}") for i in range(3)]
    text = world.refused("ELIMIT", topic="t3")
    assert text == "topic 't3': the manager already has 3 topics, its limit is 3"
    world.open(topic="t0", kind=SUB)  # existing topics still take ports
    world.registry.remove_port(ports[1])
    world.open(topic="t3")


def test_subscriber_limit_and_reader_slots() -> None:
    world = World()
    world.open()
    subs = [world.open(kind=SUB) for _ in range(64)]
    assert [s.reader_index for s in subs] == list(range(64))
    assert "already has 64 subscribers, the limit is 64" in world.refused("ELIMIT", kind=SUB)
    world.open()  # publishers are not limited by reader slots
    world.registry.remove_port(subs[10])
    world.registry.remove_port(subs[3])
    assert world.open(kind=SUB).reader_index == 3  # the lowest free slot
    assert world.open(kind=SUB).reader_index == 10


def test_ring_grows_by_doubling_at_least() -> None:
    world = World()
    assert world.open().topic.slots == 2
    world.open(kind=SUB, buffers=1)
    assert world.grown == []
    world.open(kind=SUB, buffers=2)  # needs 3 slots: doubling gives 4
    world.open(kind=SUB, buffers=3)  # fits in 4
    world.open(kind=SUB, buffers=10)  # needs 11, more than 2 x 4
    world.open(kind=PUB, buffers=12)  # a publisher may ask for a deeper ring too
    world.open(kind=SUB, buffers=1000)
    assert world.grown == [4, 11, 22, 1001]
    world.open(kind=SUB, buffers=1024)  # doubling would pass the deepest ring: capped
    assert world.grown[-1] == 1025


def test_ring_memory_limit() -> None:
    limit = ring_size(1000, 10)
    world = World(ring_memory=limit)
    world.open(size=1000, kind=SUB, buffers=9)  # exactly the limit
    world.registry.remove_port(next(iter(world.client.ports.values())))
    text = world.refused("ELIMIT", size=1000, buffers=10)
    assert text == (f"topic 'robot.state': a ring of 11 slots of 1000 bytes takes "
                    f"{ring_size(1000, 11)} bytes, the limit per topic is {limit}")
    world.open(size=1000, buffers=4)
    # growing would double to 10 slots, which is over the limit for 9: so exactly 9 it is
    world = World(ring_memory=ring_size(1000, 9))
    world.open(size=1000, buffers=4)
    world.open(size=1000, kind=SUB, buffers=8)
    assert world.grown == [9]
    world.refused("ELIMIT", size=1000, buffers=9)


def test_default_memory_limit_refuses_before_anything_is_created() -> None:
    world = World()
    assert "the limit per topic is 1073741824" in world.refused("ELIMIT", size=64 * MIB,
                                                                  buffers=16)
    assert world.registry.topics == {}


def test_topic_goes_with_its_last_port() -> None:
    world = World()
    pub = world.open()
    sub = world.open(kind=SUB, buffers=4)
    topic = pub.topic
    assert (topic.publishers, topic.subscribers, topic.readers) == (1, 1, {0: sub.id})
    assert world.registry.remove_port(pub) is False
    assert (topic.publishers, topic.subscribers) == (0, 1)
    assert world.registry.remove_port(sub) is True
    assert world.registry.topics == {} and world.client.ports == {}
    # a new topic of the same name is a new topic: new id, new md, fresh ring
    again = world.open(md="robot/other", layout_hash=1, size=8)
    assert again.topic.id == topic.id + 1 and again.topic.slots == 2


def test_ports_belong_to_their_client() -> None:
    world = World()
    port = world.open()
    other = world.registry.add_client("other", 2, "b", "v")
    assert world.registry.find_port(world.client, port.id) is port
    with pytest.raises(RequestError) as info:
        world.registry.find_port(other, port.id)
    assert info.value.code == "ENOTFOUND"
    assert info.value.text == f"client 'other' has no port {port.id}"


def test_topic_lookup() -> None:
    world = World()
    world.open()
    assert world.registry.topic("robot.state").md_name == "robot/joint_state"
    with pytest.raises(RequestError) as info:
        world.registry.topic("nope")
    assert (info.value.code, info.value.text) == ("ENOTFOUND", "no topic 'nope'")


def test_a_topic_whose_first_port_failed_is_dropped() -> None:
    world = World()
    plan = world.registry.plan_port(world.client, request())
    topic = world.registry.add_topic(plan)
    assert world.registry.drop_topic_if_unused(topic) is True
    assert world.registry.topics == {}


def test_limits_are_checked() -> None:
    with pytest.raises(ValueError):
        Limits(topics=0)
    with pytest.raises(ValueError):
        Limits(subscribers_per_topic=65)
