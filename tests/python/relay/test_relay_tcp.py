"""TCP links of ln_relay over loopback: patterned data arrives complete and in order
through loss and jitter both ways, half-close, close and reset propagate, a target that
refuses closes the client, and a stalled direction stops reading instead of growing."""

from __future__ import annotations

import asyncio
import contextlib
import socket
from collections.abc import AsyncIterator, Awaitable, Callable

import pytest

from links_and_nodes.relay import FaultSpec, Link, Relay
from links_and_nodes.relay import tcp as relay_tcp

from .conftest import WAIT, until

Handler = Callable[[asyncio.StreamReader, asyncio.StreamWriter], Awaitable[None]]


@pytest.fixture
async def tcp_server() -> AsyncIterator[Callable[[Handler], Awaitable[tuple[str, int]]]]:
    """Starts TCP servers on 127.0.0.1:0 with the given handler; closed after the test."""
    servers: list[asyncio.Server] = []

    async def start(handler: Handler) -> tuple[str, int]:
        server = await asyncio.start_server(handler, "127.0.0.1", 0)
        servers.append(server)
        return server.sockets[0].getsockname()[:2]

    yield start
    for server in servers:
        server.close()


async def echo(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
    while data := await reader.read(1 << 16):
        writer.write(data)
        await writer.drain()
    writer.close()


def pattern(size: int) -> bytes:
    """Counting 32-bit words: a byte out of place or missing shows."""
    return b"".join(i.to_bytes(4, "big") for i in range(size // 4))


async def test_data_arrives_complete_and_in_order_through_loss_and_jitter(
        tcp_server: Callable[[Handler], Awaitable[tuple[str, int]]]) -> None:
    target = await tcp_server(echo)
    faults = FaultSpec(loss=0.3, delay_ms=1, jitter_ms=1, rto_ms=2, rto_max_ms=16,
                       tcp_chunk=4096)
    data = pattern(2 << 20)
    async with Relay([Link.tcp("127.0.0.1:0", target)], faults, seed=4) as relay:
        reader, writer = await asyncio.open_connection(*relay.bound[0])

        async def send() -> None:
            writer.write(data)
            await writer.drain()
            writer.write_eof()

        sending = asyncio.create_task(send())
        back = await asyncio.wait_for(reader.read(), WAIT)
        await sending
        writer.close()
        stats = relay.stats[0]
        await until(lambda: stats.active == 0, "the relayed connection to end")
    assert back == data
    for direction in (stats.upstream, stats.downstream):
        assert direction.bytes_in == direction.bytes_out == len(data)
        assert direction.units_in == direction.units_out >= len(data) // 4096
        assert direction.lost > 0
        assert (direction.queued, direction.queued_bytes) == (0, 0)
    assert (stats.peers, stats.connect_failed, stats.aborted, stats.resets) == (1, 0, 0, 0)


async def test_half_close_propagates_both_ways(
        tcp_server: Callable[[Handler], Awaitable[tuple[str, int]]]) -> None:
    seen: list[bytes] = []

    async def answer_after_eof(reader: asyncio.StreamReader,
                               writer: asyncio.StreamWriter) -> None:
        seen.append(await reader.read())  # returns only at the client's end of stream
        writer.write(b"bye")
        writer.close()

    target = await tcp_server(answer_after_eof)
    async with Relay([Link.tcp("127.0.0.1:0", target)], FaultSpec(delay_ms=2)) as relay:
        reader, writer = await asyncio.open_connection(*relay.bound[0])
        writer.write(b"hello")
        writer.write_eof()
        assert await asyncio.wait_for(reader.read(), WAIT) == b"bye"
        writer.close()
        await until(lambda: relay.stats[0].active == 0, "the relayed connection to end")
    assert seen == [b"hello"]


async def test_target_close_reaches_the_client(
        tcp_server: Callable[[Handler], Awaitable[tuple[str, int]]]) -> None:
    async def greet_and_close(reader: asyncio.StreamReader,
                              writer: asyncio.StreamWriter) -> None:
        writer.write(b"x" * 100_000)
        await writer.drain()
        writer.close()

    target = await tcp_server(greet_and_close)
    async with Relay([Link.tcp("127.0.0.1:0", target)]) as relay:
        reader, writer = await asyncio.open_connection(*relay.bound[0])
        assert await asyncio.wait_for(reader.read(), WAIT) == b"x" * 100_000
        writer.close()


async def test_a_reset_is_passed_on(
        tcp_server: Callable[[Handler], Awaitable[tuple[str, int]]]) -> None:
    async def reset(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        await reader.readexactly(4)
        relay_tcp.reset(writer)

    target = await tcp_server(reset)
    async with Relay([Link.tcp("127.0.0.1:0", target)]) as relay:
        reader, writer = await asyncio.open_connection(*relay.bound[0])
        writer.write(b"ping")
        with pytest.raises(ConnectionResetError):
            await asyncio.wait_for(reader.read(), WAIT)
        writer.close()
        await until(lambda: relay.stats[0].resets == 1, "the reset to be counted")


async def test_a_refused_target_closes_the_client() -> None:
    with socket.socket() as closed:  # bound, not listening: connecting is refused
        closed.bind(("127.0.0.1", 0))
        async with Relay([Link.tcp("127.0.0.1:0", closed.getsockname())]) as relay:
            reader, writer = await asyncio.open_connection(*relay.bound[0])
            assert await asyncio.wait_for(reader.read(), WAIT) == b""
            writer.close()
            await until(lambda: relay.stats[0].connect_failed == 1, "the failed connect")
            assert relay.stats[0].active == 0


async def test_a_stalled_direction_stops_reading(
        tcp_server: Callable[[Handler], Awaitable[tuple[str, int]]]) -> None:
    async def never_read(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        with contextlib.suppress(ConnectionError):
            await reader.read()

    target = await tcp_server(never_read)
    faults = FaultSpec(delay_ms=600_000, queue_limit=256 << 10, tcp_chunk=16 << 10)
    async with Relay([Link.tcp("127.0.0.1:0", target)], faults) as relay:
        reader, writer = await asyncio.open_connection(*relay.bound[0])
        writer.write(b"z" * (64 << 20))  # far more than the limit and every buffer
        up = relay.stats[0].upstream
        await until(lambda: up.queued_bytes >= faults.queue_limit, "the queue to fill")
        assert up.bytes_in <= faults.queue_limit + faults.tcp_chunk
        assert up.units_out == 0
        assert writer.transport.get_write_buffer_size() > 0  # the client is held up
    # Closing the relay resets the connection and frees what it queued.
    with pytest.raises(ConnectionResetError):
        await asyncio.wait_for(reader.read(), WAIT)
    writer.close()
    assert (relay.stats[0].active, up.queued, up.queued_bytes) == (0, 0, 0)


async def test_loss_everywhere_makes_tcp_give_up(
        tcp_server: Callable[[Handler], Awaitable[tuple[str, int]]]) -> None:
    target = await tcp_server(echo)
    faults = FaultSpec(loss=1.0, rto_ms=1, rto_max_ms=4, tcp_retries=3)
    async with Relay([Link.tcp("127.0.0.1:0", target)], faults, seed=1) as relay:
        reader, writer = await asyncio.open_connection(*relay.bound[0])
        writer.write(b"lost")
        with pytest.raises(ConnectionResetError):
            await asyncio.wait_for(reader.read(), WAIT)
        writer.close()
        stats = relay.stats[0]
        await until(lambda: stats.active == 0, "the connection to end")
    assert (stats.aborted, stats.upstream.lost, stats.upstream.units_out) == (1, 4, 0)
