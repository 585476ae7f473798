"""Forwarding a topic between two daemons on this host (two "hosts" sharing /dev/shm, with
rings of different names): samples a tap writes into the sending ring arrive in the
receiving ring with their sequence numbers and data, STREAM_STATS counts them, streams
outlive the manager's connection, STREAM_REMOVE and RING_PURGE stop them, and an instance
can neither see nor touch another's streams."""

from __future__ import annotations

import asyncio
import secrets
import struct
from collections.abc import Awaitable, Callable, Iterator

import pytest
from daemonproc import WAIT, Daemon, unique_instance
from ringtap import Tap, prefix, purge

from links_and_nodes.manager.processes import daemon_client as dc
from links_and_nodes.manager.processes import daemon_wire as dw

LAYOUT, SIZE, SLOTS = 0x5EED_0002, 3000, 256  # > one UDP fragment of 1400 bytes
TOPIC, MD = "/arm/state", "lntest/pattern"
COUNT = 40  # samples sent over TCP at once (fewer than SLOTS: none overwritten)


def sample(seq: int) -> bytes:
    return struct.pack("<Q", seq) * (SIZE // 8)


def new_token() -> int:
    return secrets.randbits(63) + 1


@pytest.fixture
def pair(start: Callable[..., Daemon]) -> Iterator[tuple[Daemon, Daemon]]:
    """Daemons A (sender) and B (receiver) with one key, as the daemons of an installation
    have (forwarded data is authenticated with it); connections to both use A's instance."""
    a = start()
    b = start(key_file=a.key_file)
    yield a, b
    purge(a.instance)


async def until(check: Callable[[], Awaitable[object]], what: str) -> object:
    """Poll `check` until it returns something true; WAIT is only an upper bound."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + WAIT
    while not (value := await check()):
        if loop.time() > deadline:
            pytest.fail(f"gave up waiting for {what}")
        await asyncio.sleep(0.02)
    return value


def deliver_udp(writer: Tap, reader: Tap, first: int, wanted: int) -> list[int]:
    """Inject samples from seq `first` on until `wanted` of them arrived (UDP may lose one,
    and the newest wins, so each is read before the next is written); their seqs."""
    got: list[int] = []
    seq = first
    for _ in range(int(WAIT / 0.2)):
        writer.inject(sample(seq), seq)
        while (item := reader.read(0.2)) is not None:
            assert item == (item[0], sample(item[0]))
            got.append(item[0])
        if len(got) >= wanted:
            return got
        seq += 1
    pytest.fail(f"only {len(got)} of {wanted} samples arrived over UDP")


async def one_stream(client: dc.DaemonClient) -> dw.StreamStat:
    streams, _ = await client.stream_stats()
    assert len(streams) == 1, streams
    return streams[0]


@pytest.mark.parametrize("transport", ["udp", "tcp"])
def test_forward_a_topic(pair: tuple[Daemon, Daemon], transport: str) -> None:
    a, b = pair
    instance = a.instance
    src, dst, marker = (prefix(instance) + n for n in ("1.1", "2.1", "3.1"))
    token = new_token()

    async def setup() -> int:
        async with await a.connect(instance) as sender, \
                await b.connect(instance) as receiver:
            await sender.ring_create(src, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            for name in (dst, marker):
                await receiver.ring_create(name, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            port = (await receiver.net_info()).data_port
            assert port == b.data_port
            await receiver.stream_recv(token, dst, LAYOUT, SIZE, transport)
            await sender.stream_send(token, src, LAYOUT, SIZE, transport, "127.0.0.1", port)
            return port

    port = asyncio.run(setup())  # the connections are closed: the stream goes on
    with Tap(src, LAYOUT, SIZE) as writer, Tap(dst, LAYOUT, SIZE) as reader:
        if transport == "tcp":  # every sample, in order
            for seq in range(1, COUNT + 1):
                writer.inject(sample(seq), seq)
            got = [reader.read(WAIT) for _ in range(COUNT)]
            assert got == [(seq, sample(seq)) for seq in range(1, COUNT + 1)]
            last = COUNT
        else:
            seqs = deliver_udp(writer, reader, 1, 5)
            assert seqs == sorted(set(seqs))
            last = seqs[-1]

    async def check() -> None:
        async with await a.connect(instance) as sender, \
                await b.connect(instance) as receiver:
            assert await receiver.ring_write_seq(dst) == last

            async def counted(client: dc.DaemonClient) -> dw.StreamStat | None:
                s = await one_stream(client)
                return s if s.samples >= (COUNT if transport == "tcp" else 5) else None

            out = await until(lambda: counted(sender), "the sender's count")
            into = await until(lambda: counted(receiver), "the receiver's count")
            assert isinstance(out, dw.StreamStat) and isinstance(into, dw.StreamStat)
            assert (out.token, out.sending, out.transport, out.ring, out.peer) == \
                (token, True, transport, src, f"127.0.0.1:{port}")
            assert (into.token, into.sending, into.transport, into.ring) == \
                (token, False, transport, dst)
            assert out.connected and into.connected
            assert out.bytes >= out.samples * SIZE and into.bytes >= into.samples * SIZE
            assert into.invalid == 0 and into.stale == 0
            if transport == "tcp":
                assert (out.samples, into.samples, out.drops, into.drops) == (COUNT, COUNT, 0, 0)
            _, totals = await receiver.stream_stats()
            assert totals == dw.StreamTotals(unknown_stream=0, malformed=0)

            # Stopped at the sender: what is written afterwards does not reach `dst`.  A
            # second stream into `marker` shows when it would have arrived.
            await sender.stream_remove(token)
            assert (await sender.stream_stats())[0] == []
            second = new_token()
            await receiver.stream_recv(second, marker, LAYOUT, SIZE, transport)
            await sender.stream_send(second, src, LAYOUT, SIZE, transport, "127.0.0.1", port)
            with Tap(src, LAYOUT, SIZE) as writer, Tap(marker, LAYOUT, SIZE) as reader:
                if transport == "tcp":
                    writer.inject(sample(last + 1), last + 1)
                    assert reader.read(WAIT) == (last + 1, sample(last + 1))
                else:
                    deliver_udp(writer, reader, last + 1, 1)
            assert await receiver.ring_write_seq(dst) == last
            await refused(sender.stream_remove(token), dw.ErrorCode.UNKNOWN_STREAM)
            # A purge stops every stream of the instance (and, both "hosts" sharing
            # /dev/shm, the first one unlinks all three segments).
            assert await sender.ring_purge() == 3
            assert (await sender.stream_stats())[0] == []
            assert await receiver.ring_purge() == 0
            assert (await receiver.stream_stats())[0] == []

    asyncio.run(check())


def test_receiver_removal_makes_the_token_unknown(pair: tuple[Daemon, Daemon]) -> None:
    a, b = pair
    instance = a.instance
    src, dst = prefix(instance) + "1.1", prefix(instance) + "2.1"
    token = new_token()

    async def main() -> None:
        async with await a.connect(instance) as sender, \
                await b.connect(instance) as receiver:
            await sender.ring_create(src, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await receiver.ring_create(dst, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await receiver.stream_recv(token, dst, LAYOUT, SIZE, "udp")
            await sender.stream_send(token, src, LAYOUT, SIZE, "udp", "127.0.0.1", b.data_port)
            await receiver.stream_remove(token)
            assert (await receiver.stream_stats())[0] == []
            with Tap(src, LAYOUT, SIZE) as writer:
                seq = 0

                async def unknown() -> bool:
                    nonlocal seq
                    seq += 1
                    writer.inject(sample(seq), seq)
                    return (await receiver.stream_stats())[1].unknown_stream > 0

                await until(unknown, "datagrams of an unknown stream to be counted")
            assert await receiver.ring_write_seq(dst) == 0

    asyncio.run(main())


async def refused(call: Awaitable[object], code: dw.ErrorCode, *texts: str) -> None:
    with pytest.raises(dw.DaemonError) as e:
        await call
    assert e.value.code == code, e.value
    for text in texts:
        assert text in str(e.value)


def test_stream_requests_are_checked(daemon: Daemon) -> None:
    other = unique_instance()
    mine, theirs = prefix(daemon.instance) + "1.1", prefix(other) + "1.1"
    token = new_token()

    async def main() -> None:
        async with await daemon.connect() as client, await daemon.connect(other) as stranger:
            await client.ring_create(mine, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await stranger.ring_create(theirs, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await client.stream_recv(token, mine, LAYOUT, SIZE, "tcp")
            # Another instance neither sees, removes nor takes over the stream.
            assert await stranger.stream_stats() == ([], dw.StreamTotals(0, 0))
            await refused(stranger.stream_remove(token), dw.ErrorCode.UNKNOWN_STREAM,
                          f"no stream {token:016x} in instance {other}")
            await refused(stranger.stream_recv(token, theirs, LAYOUT, SIZE, "udp"),
                          dw.ErrorCode.STREAM_FAILED, "in use by another instance")
            await refused(client.stream_recv(new_token(), theirs, LAYOUT, SIZE, "udp"),
                          dw.ErrorCode.STREAM_FAILED, "not in the namespace")
            await refused(client.stream_send(new_token(), theirs, LAYOUT, SIZE, "udp",
                                             "127.0.0.1", 9),
                          dw.ErrorCode.STREAM_FAILED, "not in the namespace")
            # The forwarder's own refusals come with its text.
            await refused(client.stream_recv(0, mine, LAYOUT, SIZE, "udp"),
                          dw.ErrorCode.STREAM_FAILED, "token 0")
            await refused(client.stream_send(new_token(), mine, LAYOUT + 1, SIZE, "udp",
                                             "127.0.0.1", 9),
                          dw.ErrorCode.STREAM_FAILED)
            await refused(client.stream_send(new_token(), prefix(daemon.instance) + "9.9",
                                             LAYOUT, SIZE, "tcp", "127.0.0.1", 9),
                          dw.ErrorCode.STREAM_FAILED)
            with pytest.raises(dw.DaemonError) as e:
                await client.stream_recv(new_token(), mine, LAYOUT, SIZE, "sctp")
            assert e.value.code is None and "unknown transport" in str(e.value)
            (stat,) = (await client.stream_stats())[0]
            assert (stat.token, stat.sending, stat.transport) == (token, False, "tcp")
            await client.stream_remove(token)
            await refused(client.stream_remove(token), dw.ErrorCode.UNKNOWN_STREAM)
            await client.ping()

    try:
        asyncio.run(main())
    finally:
        purge(daemon.instance)
        purge(other)


@pytest.mark.parametrize("transport", ["udp", "tcp"])
def test_a_sender_with_another_key_is_rejected(start: Callable[..., Daemon],
                                               transport: str) -> None:
    """Daemons with different key files: the receiver rejects what the sender sends
    (counted as `rejected`, nothing reaches the ring); with `security: none` at both ends the
    same daemons forward."""
    a, b = start(), start()  # each its own key
    instance = a.instance
    src, dst, plain = (prefix(instance) + n for n in ("1.1", "2.1", "3.1"))
    token, open_token = new_token(), new_token()

    async def setup() -> None:
        async with await a.connect(instance) as sender, \
                await b.connect(instance) as receiver:
            await sender.ring_create(src, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            for name in (dst, plain):
                await receiver.ring_create(name, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            port = (await receiver.net_info()).data_port
            await receiver.stream_recv(token, dst, LAYOUT, SIZE, transport, "encrypt")
            await sender.stream_send(token, src, LAYOUT, SIZE, transport, "127.0.0.1", port,
                                     "encrypt")
            await receiver.stream_recv(open_token, plain, LAYOUT, SIZE, transport, "none")
            await sender.stream_send(open_token, src, LAYOUT, SIZE, transport, "127.0.0.1",
                                     port, "none")

    async def rejected() -> dw.StreamStat | None:
        async with await b.connect(instance) as receiver:
            streams, _ = await receiver.stream_stats()
            mine = {s.token: s for s in streams}
            return mine[token] if mine[token].rejected >= 2 else None

    asyncio.run(setup())
    try:
        with Tap(src, LAYOUT, SIZE) as writer, Tap(plain, LAYOUT, SIZE) as reader:
            got = deliver_udp(writer, reader, 1, 3)  # the unprotected stream delivers
            for seq in range(got[-1] + 1, got[-1] + 20):
                writer.inject(sample(seq), seq)
            stat = asyncio.run(until(rejected, "the receiver to reject the other key"))
        assert isinstance(stat, dw.StreamStat)
        assert stat.samples == 0 and stat.invalid == 0
        assert "rejected" in stat.last_error or "not authentic" in stat.last_error, stat

        async def no_samples() -> int:
            async with await b.connect(instance) as receiver:
                return await receiver.ring_write_seq(dst)

        assert asyncio.run(no_samples()) == 0
    finally:
        purge(instance)
