"""Topic rings the daemon administers for a manager on another host: created rings are real
libln rings (taps write into them, the daemon reads their sequence numbers), reader slots,
counts, retiring into a successor, removal and purging; names are confined to the
instance's namespace; handles outlive connections and segments outlive the daemon, which
adopts them again after a restart."""

from __future__ import annotations

import asyncio
import ctypes
import os
import signal
import struct
from collections.abc import Callable, Iterator

import pytest
from daemonproc import WAIT, Daemon, RawConnection, unique_instance
from ringtap import Tap, prefix, purge, ring_size, segment_size, segments_of

from links_and_nodes import _adminlib
from links_and_nodes.manager.processes import daemon_wire as dw
from links_and_nodes.wire import codec as wc

LAYOUT, SIZE, SLOTS = 0x5EED_0001, 64, 8
TOPIC, MD = "/arm/state", "lntest/pattern"


@pytest.fixture
def rings(daemon: Daemon) -> Iterator[Daemon]:
    """The daemon fixture, and every segment of its instance removed afterwards."""
    yield daemon
    purge(daemon.instance)


def sample(seq: int) -> bytes:
    return struct.pack("<Q", seq).ljust(SIZE, b"\xab")


async def refused(call: object, code: dw.ErrorCode, *texts: str) -> str:
    with pytest.raises(dw.DaemonError) as e:
        await call  # type: ignore[misc]
    assert e.value.code == code, e.value
    for text in texts:
        assert text in str(e.value)
    return str(e.value)


def test_ring_lifecycle(rings: Daemon) -> None:
    first, second = prefix(rings.instance) + "1.1", prefix(rings.instance) + "1.2"

    async def main() -> None:
        async with await rings.connect() as client:
            await client.ring_create(first, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            assert segment_size(first) == ring_size(SIZE, SLOTS)
            # A real ring: taps check its header and layout, and what one injects the other
            # reads and the daemon counts.
            with Tap(first, LAYOUT, SIZE) as reader, Tap(first, LAYOUT, SIZE) as writer:
                assert await client.ring_write_seq(first) == 0
                writer.inject(sample(1), 1)
                writer.inject(sample(2), 2)
                assert reader.read(WAIT) == (1, sample(1))
                assert reader.read(WAIT) == (2, sample(2))
            assert await client.ring_write_seq(first) == 2
            await refused(client.ring_create(first, TOPIC, MD, LAYOUT, SIZE, SLOTS),
                          dw.ErrorCode.RING_FAILED, f"ring {first} exists already")

            await client.ring_set_counts(first, 1, 2)
            await client.ring_reserve_reader(first, 0, os.getpid(), 2)
            await refused(client.ring_reserve_reader(first, 64, os.getpid(), 2),
                          dw.ErrorCode.RING_FAILED, "reserving reader slot 64 of", "EINVAL")
            await client.ring_release_reader(first, 0)

            await client.ring_create(second, TOPIC, MD, LAYOUT, SIZE, 2 * SLOTS)
            await refused(client.ring_retire(first, second, -1.0), dw.ErrorCode.RING_FAILED,
                          "retire timeout")
            await refused(client.ring_retire(first, first), dw.ErrorCode.RING_FAILED,
                          "its own successor")
            await client.ring_retire(first, second, 1.0)
            assert await client.ring_write_seq(second) == 2  # carried over
            with Tap(first, LAYOUT, SIZE) as writer:  # follows the retired ring onwards
                writer.inject(sample(3), 3)
            assert await client.ring_write_seq(second) == 3

            await client.ring_remove(first)
            assert segment_size(first) is None
            await client.ring_remove(first)  # gone already: fine
            await refused(client.ring_write_seq(first), dw.ErrorCode.RING_FAILED,
                          f"holds no ring {first}")
            await client.ring_remove(second)
            assert segments_of(rings.instance) == []
            await client.ping()  # refusals kept the connection

    asyncio.run(main())


def test_purge(rings: Daemon) -> None:
    other = unique_instance()
    leftover = prefix(rings.instance) + "9.1"

    async def main() -> None:
        mine = await rings.connect()
        theirs = await rings.connect(other)
        try:
            for n in range(3):
                await mine.ring_create(prefix(rings.instance) + f"{n}.1", TOPIC, MD, LAYOUT,
                                       SIZE, SLOTS)
            await theirs.ring_create(prefix(other) + "1.1", TOPIC, MD, LAYOUT, SIZE, SLOTS)
            # A segment the daemon never held (an earlier manager's) goes too.
            handle = _adminlib.RingAdminHandle()
            _adminlib.ln_ring_admin_create(ctypes.byref(handle), leftover.encode(), TOPIC.encode(),
                                           MD.encode(), LAYOUT, SIZE, SLOTS)
            _adminlib.ln_ring_admin_close(handle)
            assert await mine.ring_purge() == 4
            assert segments_of(rings.instance) == []
            await refused(mine.ring_write_seq(prefix(rings.instance) + "0.1"),
                          dw.ErrorCode.RING_FAILED, "holds no ring")
            assert segments_of(other) == [prefix(other) + "1.1"]
            assert await theirs.ring_write_seq(prefix(other) + "1.1") == 0
            assert await mine.ring_purge() == 0
        finally:
            await mine.close()
            await theirs.close()
            purge(other)

    asyncio.run(main())


def test_names_outside_the_namespace_are_refused(rings: Daemon) -> None:
    other = unique_instance()
    theirs_name = prefix(other) + "1.1"
    mine = prefix(rings.instance)

    async def main() -> None:
        async with await rings.connect() as client, await rings.connect(other) as theirs:
            await theirs.ring_create(theirs_name, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            outside = "not in the namespace of instance " + rings.instance
            for call in (client.ring_create(theirs_name, TOPIC, MD, LAYOUT, SIZE, SLOTS,
                                            adopt=True),
                         client.ring_write_seq(theirs_name),
                         client.ring_set_counts(theirs_name, 1, 1),
                         client.ring_reserve_reader(theirs_name, 0, 1, 1),
                         client.ring_retire(theirs_name, theirs_name),
                         client.ring_remove(theirs_name)):
                await refused(call, dw.ErrorCode.RING_FAILED, outside)
            for bad in (mine, mine[:-1], mine + "a/b", mine[1:] + "1.1", mine[:-1] + "x.1"):
                await refused(client.ring_create(bad, TOPIC, MD, LAYOUT, SIZE, SLOTS),
                              dw.ErrorCode.RING_FAILED, outside)
            assert segment_size(theirs_name) == ring_size(SIZE, SLOTS)
            assert await theirs.ring_write_seq(theirs_name) == 0
            await theirs.ring_remove(theirs_name)

    try:
        asyncio.run(main())
    finally:
        purge(other)


def test_instance_names_are_sanitized(rings: Daemon) -> None:
    instance = f"lab.{unique_instance()}/a b"
    name = f"/ln.{instance.replace('.', '_').replace('/', '_').replace(' ', '_')}.1.1"
    assert name.startswith(prefix(instance))

    async def main() -> None:
        async with await rings.connect(instance) as client:
            await client.ring_create(name, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            assert await client.ring_purge() == 1

    try:
        asyncio.run(main())
    finally:
        purge(instance)


def test_rings_outlive_the_connection(rings: Daemon) -> None:
    name = prefix(rings.instance) + "1.1"

    async def first() -> None:
        async with await rings.connect() as client:
            await client.ring_create(name, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await client.ring_reserve_reader(name, 3, os.getpid(), 2)

    async def second() -> None:
        async with await rings.connect() as client:
            assert await client.ring_write_seq(name) == 5
            await client.ring_create(name, TOPIC, MD, LAYOUT, SIZE, SLOTS, adopt=True)
            await refused(client.ring_create(name, TOPIC, MD, LAYOUT, SIZE, 2 * SLOTS,
                                             adopt=True),
                          dw.ErrorCode.RING_FAILED, "exists with")
            await client.ring_release_reader(name, 3)

    asyncio.run(first())
    with Tap(name, LAYOUT, SIZE) as writer:  # a client goes on using it meanwhile
        writer.inject(sample(5), 5)
    asyncio.run(second())


def test_adopt_after_a_daemon_restart(start: Callable[..., Daemon]) -> None:
    old = start()
    instance = old.instance
    name = prefix(instance) + "1.1"

    async def before() -> None:
        async with await old.connect() as client:
            await client.ring_create(name, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            with Tap(name, LAYOUT, SIZE) as writer:
                writer.inject(sample(7), 7)

    async def after(new: Daemon) -> None:
        async with await new.connect(instance) as client:
            await refused(client.ring_write_seq(name), dw.ErrorCode.RING_FAILED,
                          "holds no ring")
            await refused(client.ring_create(name, TOPIC, MD, LAYOUT, SIZE, SLOTS),
                          dw.ErrorCode.RING_FAILED, f"creating segment {name}", "File exists")
            await refused(client.ring_create(name, TOPIC, MD, LAYOUT + 1, SIZE, SLOTS,
                                             adopt=True),
                          dw.ErrorCode.RING_FAILED, f"adopting segment {name}", "ELAYOUT")
            await client.ring_create(name, TOPIC, MD, LAYOUT, SIZE, SLOTS, adopt=True)
            assert await client.ring_write_seq(name) == 7
            # adopt of a segment that is not there creates it
            await client.ring_create(prefix(instance) + "2.1", TOPIC, MD, LAYOUT, SIZE, SLOTS,
                                     adopt=True)

    try:
        asyncio.run(before())
        old.proc.send_signal(signal.SIGKILL)
        old.proc.wait(WAIT)
        assert segment_size(name) == ring_size(SIZE, SLOTS)
        new = start()
        asyncio.run(after(new))
        # A daemon that ends normally leaves the segments too.
        new.proc.send_signal(signal.SIGTERM)
        assert new.proc.wait(WAIT) == 0
        assert segments_of(instance) == [name, prefix(instance) + "2.1"]
    finally:
        purge(instance)


def _create(name: str, adopt: int) -> bytes:
    return (wc.encode_str(name) + wc.encode_str(TOPIC) + wc.encode_str(MD)
            + struct.pack("<QQIB", LAYOUT, SIZE, SLOTS, adopt))


MALFORMED = {
    "truncated RING_CREATE": (dw.Msg.RING_CREATE, lambda n: _create(n, 0)[:-1]),
    "RING_CREATE with trailing bytes": (dw.Msg.RING_CREATE, lambda n: _create(n, 0) + b"\0"),
    "RING_CREATE with adopt 2": (dw.Msg.RING_CREATE, lambda n: _create(n, 2)),
    "RING_READER with reserve 2": (dw.Msg.RING_READER,
                                   lambda n: wc.encode_str(n) + struct.pack("<IiIB", 0, 1, 1, 2)),
    "RING_RETIRE without timeout": (dw.Msg.RING_RETIRE, lambda n: wc.encode_str(n) + wc.encode_str(n)),
    "RING_PURGE with a payload": (dw.Msg.RING_PURGE, lambda n: b"\0"),
    "NET_INFO with a payload": (dw.Msg.NET_INFO, lambda n: b"\0"),
    "STREAM_SEND with transport 2": (
        dw.Msg.STREAM_SEND, lambda n: struct.pack("<Q", 1) + wc.encode_str(n)
        + struct.pack("<QQB", LAYOUT, SIZE, 2) + wc.encode_str("127.0.0.1") + struct.pack("<H", 1)),
    "STREAM_REMOVE of four bytes": (dw.Msg.STREAM_REMOVE, lambda n: b"\0" * 4),
    "RING_SEQ of an overlong name": (dw.Msg.RING_SEQ, lambda n: wc.encode_str(n + "x" * 300)),
}


@pytest.mark.parametrize("case", sorted(MALFORMED))
def test_malformed_requests_close_the_connection(rings: Daemon, case: str) -> None:
    mtype, payload = MALFORMED[case]
    raw = RawConnection(rings.port)
    try:
        raw.authenticate(rings.key, rings.instance)
        raw.send(raw.frame(mtype, 7, payload(prefix(rings.instance) + "1.1")))
        code, text = raw.expect_error_and_close()
    finally:
        raw.close()
    assert code == dw.ErrorCode.BAD_REQUEST
    assert text == f"malformed {mtype.name} request"
    assert segments_of(rings.instance) == []


def test_ring_requests_before_the_handshake_are_refused(rings: Daemon) -> None:
    raw = RawConnection(rings.port)
    try:
        raw.hello()
        raw.send(raw.frame(dw.Msg.RING_CREATE, 1, _create(prefix(rings.instance) + "1.1", 0),
                           tagged=False))
        code, text = raw.expect_error_and_close()
    finally:
        raw.close()
    assert code == dw.ErrorCode.NOT_AUTHENTICATED
    assert text == "not authenticated: RING_CREATE refused before the handshake"
    assert segments_of(rings.instance) == []
