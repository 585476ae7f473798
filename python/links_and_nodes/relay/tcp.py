"""A TCP link of ln_relay: each connection to LISTEN gets its own connection to TARGET and
two pipes, one per direction, that read chunks, hold each until its StreamShaper time and
write them on in order.  End of stream is passed on as a half-close behind the data; a
reset, a failed write or TCP giving up on a chunk resets both sides."""

from __future__ import annotations

import asyncio
import itertools
import random
import socket
import struct

from .addresses import Address, bound_socket, resolve
from .faults import FaultSpec
from .shaping import StreamShaper
from .stats import DOWNSTREAM, UPSTREAM, DirectionStats, LinkStats


class _GaveUp(Exception):
    """A chunk was lost more than FaultSpec.tcp_retries times in a row."""


def reset(writer: asyncio.StreamWriter) -> None:
    """Close with an RST, as the peer that reset or gave up did: a linger time of 0,
    then close (a plain abort would send a FIN, which reads as an orderly end)."""
    sock = writer.get_extra_info("socket")
    if sock is not None:
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        except OSError:
            pass
    writer.transport.abort()


class _Pipe:
    """One direction of one connection.  The reader stops reading while queue_limit bytes
    wait, so a slow receiver or a long delay pushes back on the sender (TCP flow control)
    instead of filling memory."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter,
                 faults: FaultSpec, rng: random.Random, stats: DirectionStats) -> None:
        self._reader = reader
        self._writer = writer
        self._faults = faults
        self._shaper = StreamShaper(faults, rng, stats)
        self._stats = stats
        self._queue: asyncio.Queue[tuple[float, bytes | None, bool]] = asyncio.Queue()
        self._queued = 0  # chunks read and not yet written
        self._queued_bytes = 0
        self._room = asyncio.Event()

    async def read(self) -> None:
        loop = asyncio.get_running_loop()
        faults = self._faults
        while True:
            while self._queued_bytes >= faults.queue_limit:
                self._room.clear()
                await self._room.wait()
            data = await self._reader.read(faults.tcp_chunk)
            now = loop.time()
            if not data:
                self._queue.put_nowait((self._shaper.eof_due(now), None, False))
                return
            due, give_up = self._shaper.admit(len(data), now)
            self._account(1, len(data))
            self._queue.put_nowait((due, data, give_up))
            if give_up:
                return

    async def write(self) -> None:
        loop = asyncio.get_running_loop()
        while True:
            due, data, give_up = await self._queue.get()
            wait = due - loop.time()
            if wait > 0:
                await asyncio.sleep(wait)
            if give_up:
                raise _GaveUp
            if data is None:
                if self._writer.can_write_eof():
                    self._writer.write_eof()
                return
            self._writer.write(data)
            await self._writer.drain()
            self._account(-1, -len(data))
            self._stats.sent(len(data))
            self._room.set()

    def discard(self) -> None:
        """Take what is still queued out of the link's queued counts (the connection
        ended)."""
        self._account(-self._queued, -self._queued_bytes)

    def _account(self, chunks: int, size: int) -> None:
        self._queued += chunks
        self._queued_bytes += size
        self._stats.queued += chunks
        self._stats.queued_bytes += size


class TcpLink:
    """Accepts connections on `listen` and relays each to its own connection to
    `target`.  Connection n's directions draw from random.Random(f"{seed}/{n}/...")."""

    def __init__(self, listen: Address, target: Address, faults: FaultSpec, seed: str,
                 stats: LinkStats) -> None:
        self._listen = listen
        self._target = target
        self._faults = faults
        self._seed = seed
        self.stats = stats
        self._server: asyncio.Server | None = None
        self._tasks: set[asyncio.Task[None]] = set()
        self._numbers = itertools.count()
        self.bound: Address | None = None

    async def start(self) -> None:
        family, sockaddr = await resolve(self._listen, socket.SOCK_STREAM, passive=True)
        self._target_family, self._target_addr = await resolve(
            self._target, socket.SOCK_STREAM, passive=False)
        sock = bound_socket(family, socket.SOCK_STREAM, sockaddr)
        try:
            self.bound = sock.getsockname()[:2]
            self._server = await asyncio.start_server(self._serve, sock=sock)
        except BaseException:
            sock.close()
            raise

    async def close(self) -> None:
        if self._server is not None:
            self._server.close()
        for task in list(self._tasks):
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        if self._server is not None:
            await self._server.wait_closed()
            self._server = None

    async def _serve(self, client_reader: asyncio.StreamReader,
                     client_writer: asyncio.StreamWriter) -> None:
        task = asyncio.current_task()
        assert task is not None
        self._tasks.add(task)
        number = next(self._numbers)
        self.stats.peers += 1
        self.stats.active += 1
        try:
            target = await self._connect()
            if target is None:
                self.stats.connect_failed += 1
                client_writer.close()
                return
            await self._relay(number, (client_reader, client_writer), target)
        finally:
            if not client_writer.transport.is_closing():  # cancelled while connecting
                reset(client_writer)
            self.stats.active -= 1
            self._tasks.discard(task)

    async def _connect(self) -> tuple[asyncio.StreamReader, asyncio.StreamWriter] | None:
        sock = socket.socket(self._target_family, socket.SOCK_STREAM)
        try:
            sock.setblocking(False)
            await asyncio.get_running_loop().sock_connect(sock, self._target_addr)
            return await asyncio.open_connection(sock=sock)
        except OSError:
            sock.close()
            return None
        except BaseException:
            sock.close()
            raise

    async def _relay(self, number: int,
                     client: tuple[asyncio.StreamReader, asyncio.StreamWriter],
                     target: tuple[asyncio.StreamReader, asyncio.StreamWriter]) -> None:
        faults = self._faults
        pipes = [_Pipe(client[0], target[1], faults.for_direction(True),
                       random.Random(f"{self._seed}/{number}/{UPSTREAM}"),
                       self.stats.upstream),
                 _Pipe(target[0], client[1], faults.for_direction(False),
                       random.Random(f"{self._seed}/{number}/{DOWNSTREAM}"),
                       self.stats.downstream)]
        clean = False
        try:
            async with asyncio.TaskGroup() as group:
                for pipe in pipes:
                    group.create_task(pipe.read())
                    group.create_task(pipe.write())
            clean = True
        except* _GaveUp:
            self.stats.aborted += 1
        except* OSError:
            self.stats.resets += 1
        finally:
            for pipe in pipes:
                pipe.discard()
            for writer in (client[1], target[1]):
                if clean:
                    writer.close()
                else:
                    reset(writer)
