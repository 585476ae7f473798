"""PUBLISH, SUBSCRIBE, CLOSE_PORT and TOPIC_INFO against a running ln_manager: the
segments it creates in /dev/shm (names, sizes, generations), reader slots, every refusal
with its code and text, and the limits."""

from __future__ import annotations

from collections.abc import Callable

import lnwire
import pytest
from mgrproc import SHM, Manager, require_manager_library, segments, unique_instance

require_manager_library()

import links_and_nodes as ln  # noqa: E402  (after the skip check)
from links_and_nodes.manager.registry.segments import ring_segment_size  # noqa: E402

Start = Callable[..., Manager]
MIB = 1 << 20
MD = "robot/joint_state"
HASH = 0x8BADF00D12345678
SIZE = 184


def shm_size(segment: str) -> int:
    assert segment.startswith("/")
    return (SHM / segment[1:]).stat().st_size


def test_publish_and_subscribe(manager: Manager) -> None:
    inst = manager.instance
    with manager.client("ctl") as client:
        pub = client.publish("robot.state", MD, HASH, SIZE)
        assert pub.type == lnwire.PORT_OK
        assert pub.segment == f"/ln.{inst}.1.1"
        assert pub.reader_index == lnwire.NO_READER
        assert shm_size(pub.segment) == ring_segment_size(SIZE, 2)
        sub = client.subscribe("robot.state", MD, HASH, SIZE)
        assert (sub.segment, sub.reader_index) == (pub.segment, 0)
        assert len({pub.port_id, sub.port_id}) == 2
        assert client.subscribe("robot.state", MD, HASH, SIZE).reader_index == 1
        other = client.subscribe("robot.cmd", "robot/command", 7, 16)
        assert (other.segment, other.reader_index) == (f"/ln.{inst}.2.1", 0)
        assert segments(inst) == [f"ln.{inst}.1.1", f"ln.{inst}.2.1"]
        info = client.topic_info("robot.state")
        assert info.type == lnwire.TOPIC_INFO_OK
        assert (info.md_name, info.layout_hash, info.message_size, info.publishers,
                info.subscribers) == (MD, HASH, SIZE, 1, 2)


def test_deeper_subscribers_get_a_new_generation(manager: Manager) -> None:
    inst = manager.instance
    with manager.client("ctl") as client:
        first = client.subscribe("cam", "cam/frame", 1, 1000)
        queued = client.subscribe("cam", "cam/frame", 1, 1000, buffers=4)
        assert queued.segment == f"/ln.{inst}.1.2"
        assert shm_size(queued.segment) == ring_segment_size(1000, 5)  # max(4 + 1, 2 x 2)
        deeper = client.subscribe("cam", "cam/frame", 1, 1000, buffers=5)
        assert deeper.segment == f"/ln.{inst}.1.3"
        assert shm_size(deeper.segment) == ring_segment_size(1000, 10)  # max(5 + 1, 2 x 5)
        assert [first.reader_index, queued.reader_index, deeper.reader_index] == [0, 1, 2]
        fits = client.publish("cam", "cam/frame", 1, 1000, buffers=9)
        assert fits.segment == deeper.segment
        # older generations stay until the topic is gone: clients move over lazily
        assert segments(inst) == [f"ln.{inst}.1.{g}" for g in (1, 2, 3)]
        for port in (first, queued, deeper):
            assert client.close_port(port.port_id).type == lnwire.OK
        assert len(segments(inst)) == 3  # the publisher still holds the topic
        assert client.close_port(fits.port_id).type == lnwire.OK
        assert segments(inst) == []
        again = client.publish("cam", "cam/frame", 1, 1000)
        assert again.segment == f"/ln.{inst}.2.1"  # a new topic, a new id


def test_reader_slots_are_reused(manager: Manager) -> None:
    with manager.client("ctl") as client:
        subs = [client.subscribe("t", "m/d", 1, 8) for _ in range(3)]
        assert client.close_port(subs[1].port_id).type == lnwire.OK
        assert client.subscribe("t", "m/d", 1, 8).reader_index == 1


def test_layout_mismatch(manager: Manager) -> None:
    with manager.client("a") as first, manager.client("b") as second:
        assert first.publish("robot.state", MD, 0x1111, 184).type == lnwire.PORT_OK
        error = second.subscribe("robot.state", MD, 0x2222, 180)
        assert (error.type, error.code) == (lnwire.ERROR, ln.LnLayoutError.code)
        assert error.text == (
            "topic 'robot.state': layout of md 'robot/joint_state' (hash 0x0000000000002222, "
            "180 bytes) differs from the topic's md 'robot/joint_state' (hash "
            "0x0000000000001111, 184 bytes)")
        info = second.topic_info("robot.state")
        assert (info.publishers, info.subscribers) == (1, 0)
    manager.wait_log(r"client b \(.*\): SUBSCRIBE refused: ELAYOUT: topic 'robot.state'")


@pytest.mark.parametrize("topic, md", [
    ("", MD), (".hidden", MD), ("has space", MD), ("t" * 256, MD), ("ümlaut", MD),
    ("ok", ""), ("ok", "robot//x"), ("ok", "robot/9lives"), ("ok", "m" * 256),
])
def test_bad_names(manager: Manager, topic: str, md: str) -> None:
    with manager.client("ctl") as client:
        error = client.publish(topic, md, 1, 8)
        assert (error.type, error.code) == (lnwire.ERROR, ln.LnInvalError.code)
        assert "name" in error.text


@pytest.mark.parametrize("size, buffers, what", [
    (0, 1, "message size 0 out of range 1..67108864"),
    (64 * MIB + 1, 1, "message size 67108865 out of range 1..67108864"),
    (8, 0, "0 buffers out of range 1..1024"),
    (8, 1025, "1025 buffers out of range 1..1024"),
    (64 * MIB, 16, "the limit per topic is 1073741824"),
])
def test_limits(manager: Manager, size: int, buffers: int, what: str) -> None:
    with manager.client("ctl") as client:
        error = client.subscribe("big", "m/d", 1, size, buffers=buffers)
        assert (error.type, error.code) == (lnwire.ERROR, ln.LnLimitError.code)
        assert what in error.text
        assert segments(manager.instance) == []


def test_largest_ring_is_accepted(manager: Manager) -> None:
    with manager.client("ctl") as client:
        reply = client.subscribe("deep", "m/d", 1, 8, buffers=1024)
        assert shm_size(reply.segment) == ring_segment_size(8, 1025)


def test_65th_subscriber(manager: Manager) -> None:
    with manager.client("ctl") as client:
        readers = [client.subscribe("busy", "m/d", 1, 8).reader_index for _ in range(64)]
        assert sorted(readers) == list(range(64))
        error = client.subscribe("busy", "m/d", 1, 8)
        assert (error.type, error.code) == (lnwire.ERROR, ln.LnLimitError.code)
        assert error.text == "topic 'busy' already has 64 subscribers, the limit is 64"
        assert client.publish("busy", "m/d", 1, 8).type == lnwire.PORT_OK
        assert client.topic_info("busy").subscribers == 64


def test_topic_limit(start_manager: Start, instance: str) -> None:
    manager = start_manager(instance, "--topic-limit", "3")
    with manager.client("ctl") as client:
        ports = [client.publish(f"t{i}", "m/d", 1, 8) for i in range(3)]
        error = client.publish("t3", "m/d", 1, 8)
        assert (error.type, error.code) == (lnwire.ERROR, ln.LnLimitError.code)
        assert error.text == "topic 't3': the manager already has 3 topics, its limit is 3"
        assert client.subscribe("t1", "m/d", 1, 8).type == lnwire.PORT_OK
        client.close_port(ports[0].port_id)
        assert client.publish("t3", "m/d", 1, 8).type == lnwire.PORT_OK


def test_ring_memory_limit_option(start_manager: Start, instance: str) -> None:
    limit = ring_segment_size(4096, 8)
    manager = start_manager(instance, "--ring-memory-limit", str(limit))
    with manager.client("ctl") as client:
        assert client.subscribe("t", "m/d", 1, 4096, buffers=7).type == lnwire.PORT_OK
        error = client.subscribe("t", "m/d", 1, 4096, buffers=8)
        assert (error.type, error.code) == (lnwire.ERROR, ln.LnLimitError.code)
        assert f"the limit per topic is {limit}" in error.text


def test_close_port(manager: Manager) -> None:
    with manager.client("a") as owner, manager.client("b") as stranger:
        port = owner.publish("t", "m/d", 1, 8)
        error = owner.close_port(port.port_id + 1000)
        assert (error.type, error.code) == (lnwire.ERROR, ln.LnNotfoundError.code)
        assert error.text == f"client 'a' has no port {port.port_id + 1000}"
        # another client's port is not found either
        error = stranger.close_port(port.port_id)
        assert (error.type, error.code) == (lnwire.ERROR, ln.LnNotfoundError.code)
        assert owner.close_port(port.port_id).type == lnwire.OK
        error = owner.close_port(port.port_id)  # twice
        assert error.code == ln.LnNotfoundError.code


def test_topic_info_counts(manager: Manager) -> None:
    with manager.client("a") as a, manager.client("b") as b:
        unknown = a.topic_info("nothing")
        assert (unknown.type, unknown.code) == (lnwire.ERROR, ln.LnNotfoundError.code)
        assert unknown.text == "no topic 'nothing'"
        pubs = [a.publish("t", "m/first", 5, 8) for _ in range(2)]
        subs = [b.subscribe("t", "m/second", 5, 8) for _ in range(3)]
        info = b.topic_info("t")
        assert (info.md_name, info.layout_hash, info.message_size) == ("m/first", 5, 8)
        assert (info.publishers, info.subscribers) == (2, 3)
        a.close_port(pubs[0].port_id)
        b.close_port(subs[2].port_id)
        info = a.topic_info("t")
        assert (info.publishers, info.subscribers) == (1, 2)


def test_flags_are_reserved_and_ignored(manager: Manager) -> None:
    with manager.client("ctl") as client:
        assert client.publish("t", "m/d", 1, 8, flags=1).type == lnwire.PORT_OK


def test_instance_names_are_sanitized(start_manager: Start) -> None:
    base = unique_instance()
    manager = start_manager(f"{base}.dots/and ü")
    with manager.client("ctl") as client:
        reply = client.publish("t", "m/d", 1, 8)
        assert reply.segment == f"/ln.{base}_dots_and__.1.1"
    assert manager.stop() == 0
    assert segments(f"{base}_dots_and__") == []


def test_failed_segment_operations_change_nothing(manager: Manager) -> None:
    """A segment that cannot be created (here: its name is taken) is refused, and the
    registry stays as it was: the same request works once the obstacle is gone."""
    inst = manager.instance
    blocker = SHM / f"ln.{inst}.1.1"
    blocker.write_bytes(b"not a ring")
    with manager.client("ctl") as client:
        error = client.publish("t", "m/d", 1, 8)
        assert error.type == lnwire.ERROR
        assert error.code in (ln.LnExistError.code, ln.LnSysError.code)
        assert f"creating segment /ln.{inst}.1.1" in error.text
        assert blocker.read_bytes() == b"not a ring"  # someone else's file stays untouched
        assert client.topic_info("t").code == ln.LnNotfoundError.code
        blocker.unlink()
        assert client.publish("t", "m/d", 1, 8).segment == f"/ln.{inst}.1.1"

        blocker = SHM / f"ln.{inst}.1.2"
        blocker.write_bytes(b"")
        error = client.subscribe("t", "m/d", 1, 8, buffers=4)  # would grow into .2
        assert f"creating segment /ln.{inst}.1.2" in error.text
        info = client.topic_info("t")
        assert (info.publishers, info.subscribers) == (1, 0)
        assert client.subscribe("t", "m/d", 1, 8).segment == f"/ln.{inst}.1.1"
        blocker.unlink()
        grown = client.subscribe("t", "m/d", 1, 8, buffers=4)
        assert (grown.segment, grown.reader_index) == (f"/ln.{inst}.1.2", 1)
