"""Pull topics served by the daemon itself: PULL_TOPIC through the Python daemon client makes
the daemon answer NDN Interests (encoded by python-ndn, an independent implementation) on a
UDP port with the samples a publisher writes into the ring; refusals carry their reason;
bad datagrams are counted; a topic belongs to its instance and keeps serving after the
manager's connection closed; PULL_REMOVE frees the port."""

from __future__ import annotations

import asyncio
import socket
import struct
from collections.abc import Iterator

import pytest
from daemonproc import WAIT, Daemon
from ringtap import Tap, prefix, purge

from links_and_nodes.manager.processes import daemon_client as dc
from links_and_nodes.manager.processes import daemon_wire as dw

ndn_encoding = pytest.importorskip("ndn.encoding")

LAYOUT, SIZE, SLOTS = 0x5EED_0051, 48, 16
TOPIC, MD = "/arm/state", "lntest/pattern"
NAME = "/ln/pulltest/arm/state"


def sample(seq: int) -> bytes:
    return struct.pack("<Q", seq).ljust(SIZE, b"\xab")


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture
def served(daemon: Daemon) -> Iterator[Daemon]:
    """The daemon fixture, and every segment of its instance removed afterwards."""
    yield daemon
    purge(daemon.instance)


def content_fields(content: bytes) -> dict[int, bytes]:
    """The pull content's TLVs by type (0x80 latest, 0x82 time, 0x84 period, 0x86 payload)."""
    fields, pos = {}, 0
    while pos < len(content):
        typ, n = ndn_encoding.parse_tl_num(content, pos)
        pos += n
        size, n = ndn_encoding.parse_tl_num(content, pos)
        pos += n
        fields[typ] = bytes(content[pos:pos + size])
        pos += size
    return fields


def number(value: bytes) -> int:
    return int.from_bytes(value, "big")


class Consumer:
    """A UDP socket that sends Interests to the pull port and decodes the Data it gets."""

    def __init__(self, port: int) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.settimeout(WAIT)
        self.to = ("127.0.0.1", port)
        self.nonce = 1

    def close(self) -> None:
        self.sock.close()

    def ask(self, uri: str, sync: bool = False) -> tuple[str, int, dict[int, bytes]]:
        """(Data name, ContentType, content fields) of the reply to an Interest for uri."""
        self.nonce += 1
        param = ndn_encoding.InterestParam(nonce=self.nonce, lifetime=2000,
                                           can_be_prefix=sync, must_be_fresh=sync)
        self.sock.sendto(bytes(ndn_encoding.make_interest(uri, param)), self.to)
        wire = self.sock.recv(65536)
        name, meta, content, _ = ndn_encoding.parse_data(wire)
        return (ndn_encoding.Name.to_str(name), meta.content_type or 0,
                content_fields(bytes(content or b"")))


async def topic_status(client: dc.DaemonClient) -> object:
    (t,) = (await client.pull_status(TOPIC)).topics
    return t


async def until_latest(client: dc.DaemonClient, seq: int) -> None:
    loop = asyncio.get_running_loop()
    deadline = loop.time() + WAIT
    while (await topic_status(client)).latest_seq != seq:
        if loop.time() > deadline:
            pytest.fail(f"the pull topic never stored seq {seq}")
        await asyncio.sleep(0.01)


def test_serves_a_topic_over_udp(served: Daemon) -> None:
    ring = prefix(served.instance) + "1.1"
    port = free_udp_port()

    async def configure() -> None:
        async with await served.connect() as client:
            await client.ring_create(ring, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await client.pull_topic(TOPIC, ring, MD, LAYOUT, SIZE, "127.0.0.1", port, NAME,
                                    16, 700)
            with pytest.raises(dw.DaemonError) as e:
                await client.pull_topic("/other", ring, MD, LAYOUT, SIZE, "127.0.0.1", port,
                                        NAME, 16, 700)
            assert e.value.code == dw.ErrorCode.LOGGER_FAILED
            assert f"name '{NAME}' is served already on 127.0.0.1:{port}" in str(e.value)
            with pytest.raises(dw.DaemonError) as e:
                await client.pull_topic("/big", ring, MD, LAYOUT, 8001, "127.0.0.1", port,
                                        NAME + "2", 16, 700)
            assert "message size 8001 out of range 1..8000" in str(e.value)
            consumer = Consumer(port)
            try:
                name, ctype, fields = consumer.ask(NAME + "/sync", sync=True)
                assert (name, ctype, number(fields[0x80])) == (NAME + "/sync", 3, 0)
                with Tap(ring, LAYOUT, SIZE) as publisher:
                    for seq in range(1, 6):
                        publisher.inject(sample(seq), seq, 1_700_000_000_000_000_000 + seq)
                await until_latest(client, 5)
                name, ctype, fields = consumer.ask(NAME + "/sync", sync=True)
                assert (name, ctype) == (NAME + "/sync/seq=5", 0)
                assert number(fields[0x80]) == 5
                assert number(fields[0x82]) == 1_700_000_000_000_000_005 // 1000
                assert fields[0x86] == sample(5)
                name, ctype, fields = consumer.ask(NAME + "/seq=3")
                assert (name, ctype, fields[0x86]) == (NAME + "/seq=3", 0, sample(3))
                consumer.sock.sendto(b"\x05\x03\x07", consumer.to)  # cut off: counted as bad
            finally:
                consumer.close()
            status = await client.pull_status()
            (p,) = status.ports
            assert (p.address, p.port) == ("127.0.0.1", port)
            (t,) = status.topics
            assert (t.topic, t.name, t.ring, t.history) == (TOPIC, NAME, ring, 16)
            assert (t.interests, t.syncs, t.data, t.nacks) == (3, 2, 2, 1)

    async def reconnect() -> None:
        # the topic is the instance's: it kept serving while nobody was connected
        consumer = Consumer(port)
        try:
            name, _, fields = consumer.ask(NAME + "/seq=4")
            assert (name, fields[0x86]) == (NAME + "/seq=4", sample(4))
        finally:
            consumer.close()
        async with await served.connect() as client:
            (p,) = (await client.pull_status()).ports
            assert (p.packets, p.bad, p.unknown, p.other) == (5, 1, 0, 0)
            await client.pull_remove()
            status = await client.pull_status()
            assert (status.ports, status.topics) == ([], [])
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            s.bind(("127.0.0.1", port))  # the port is free again

    asyncio.run(configure())
    asyncio.run(reconnect())
