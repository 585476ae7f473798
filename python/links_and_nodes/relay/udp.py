"""A UDP link of ln_relay: datagrams to LISTEN go to TARGET from a socket of their own
per client (so the target's replies find their way back to that client), through one
DatagramShaper per direction.  Plain non-blocking sockets on the event loop's reader
callbacks: a datagram the kernel will not take right now is dropped and counted, as a
network would, instead of piling up in a transport buffer."""

from __future__ import annotations

import asyncio
import random
import socket
from collections import OrderedDict
from collections.abc import Callable
from typing import Any, Generic, TypeVar

from .addresses import Address, bound_socket, enlarge_buffers, resolve
from .faults import FaultSpec
from .shaping import DatagramShaper
from .stats import DOWNSTREAM, UPSTREAM, DirectionStats, LinkStats

MAX_DATAGRAM = 65536  # above the largest UDP payload over IPv4 or IPv6 (without jumbograms)
READ_BATCH = 256  # datagrams read per wake-up, so that one busy socket cannot starve the rest

T = TypeVar("T")
SockAddr = tuple[Any, ...]  # as recvfrom gives it: (host, port) or, IPv6, with flow and scope


class _Scheduler(Generic[T]):
    """Runs a DatagramShaper on the event loop: sends what is due, then sleeps until the
    next thing is (one timer per direction)."""

    def __init__(self, loop: asyncio.AbstractEventLoop, shaper: DatagramShaper[T],
                 send: Callable[[T], bool]) -> None:
        self._loop = loop
        self.shaper = shaper
        self._send = send
        self._timer: asyncio.TimerHandle | None = None

    def push(self, item: T, size: int) -> None:
        self.shaper.push(item, size, self._loop.time())
        self.run()

    def run(self) -> None:
        stats = self.shaper.stats
        for item, size in self.shaper.pop_due(self._loop.time()):
            if self._send(item):
                stats.sent(size)
            else:
                stats.errors += 1
        wakeup = self.shaper.next_wakeup()
        if wakeup is None:
            return
        if self._timer is not None:
            if self._timer.when() <= wakeup:
                return
            self._timer.cancel()
        self._timer = self._loop.call_at(wakeup, self._fire)

    def close(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        self.shaper.clear()

    def _fire(self) -> None:
        self._timer = None
        self.run()


class _Client:
    """One client of the link: its address and the socket that talks to the target."""

    __slots__ = ("addr", "sock", "last_seen")

    def __init__(self, addr: SockAddr, sock: socket.socket, now: float) -> None:
        self.addr = addr
        self.sock = sock
        self.last_seen = now


class UdpLink:
    """Relays datagrams between clients of `listen` and `target`.  A client's upstream
    socket goes after `idle_s` seconds without traffic either way, or when more than
    `max_clients` clients are active (the longest idle first), as a NAT entry would."""

    def __init__(self, listen: Address, target: Address, faults: FaultSpec, seed: str,
                 stats: LinkStats, *, idle_s: float = 120.0, max_clients: int = 4096) -> None:
        self._listen = listen
        self._target = target
        self._faults = faults
        self._seed = seed
        self.stats = stats
        self._idle_s = idle_s
        self._max_clients = max_clients
        self._sock: socket.socket | None = None
        self._clients: OrderedDict[SockAddr, _Client] = OrderedDict()
        self._sweeper: asyncio.TimerHandle | None = None
        self.bound: Address | None = None

    async def start(self) -> None:
        self._loop = loop = asyncio.get_running_loop()
        family, sockaddr = await resolve(self._listen, socket.SOCK_DGRAM, passive=True)
        self._target_family, self._target_addr = await resolve(
            self._target, socket.SOCK_DGRAM, passive=False)
        self._up = _Scheduler[tuple[_Client, bytes]](
            loop, self._shaper(UPSTREAM, self.stats.upstream), self._send_up)
        self._down = _Scheduler[tuple[SockAddr, bytes]](
            loop, self._shaper(DOWNSTREAM, self.stats.downstream), self._send_down)
        self._sock = bound_socket(family, socket.SOCK_DGRAM, sockaddr)
        self.bound = self._sock.getsockname()[:2]
        loop.add_reader(self._sock.fileno(), self._on_listen_readable)
        self._sweeper = loop.call_later(self._idle_s / 2, self._sweep)

    def _shaper(self, direction: str, stats: DirectionStats) -> DatagramShaper:
        return DatagramShaper(self._faults.for_direction(direction == UPSTREAM),
                              random.Random(f"{self._seed}/{direction}"), stats)

    async def close(self) -> None:
        if self._sweeper is not None:
            self._sweeper.cancel()
            self._sweeper = None
        if self._sock is not None:
            self._loop.remove_reader(self._sock.fileno())
            self._sock.close()
            self._sock = None
            self._up.close()
            self._down.close()
        for addr in list(self._clients):
            self._forget(addr)

    def _on_listen_readable(self) -> None:
        assert self._sock is not None
        for _ in range(READ_BATCH):
            try:
                data, addr = self._sock.recvfrom(MAX_DATAGRAM)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:  # an ICMP error about an earlier reply to a client
                self.stats.downstream.errors += 1
                continue
            client = self._client(addr)
            if client is None:
                self.stats.upstream.errors += 1
                continue
            self._up.push((client, data), len(data))

    def _client(self, addr: SockAddr) -> _Client | None:
        now = self._loop.time()
        client = self._clients.get(addr)
        if client is not None:
            self._clients.move_to_end(addr)
            client.last_seen = now
            return client
        if len(self._clients) >= self._max_clients:
            self._forget(next(iter(self._clients)))
        sock = socket.socket(self._target_family, socket.SOCK_DGRAM)
        try:
            sock.setblocking(False)
            enlarge_buffers(sock)
            sock.connect(self._target_addr)  # replies from anyone else are not taken
        except OSError:
            sock.close()
            return None
        client = self._clients[addr] = _Client(addr, sock, now)
        self._loop.add_reader(sock.fileno(), self._on_upstream_readable, client)
        self.stats.peers += 1
        self.stats.active += 1
        return client

    def _forget(self, addr: SockAddr) -> None:
        client = self._clients.pop(addr)
        self._loop.remove_reader(client.sock.fileno())
        client.sock.close()
        self.stats.active -= 1

    def _on_upstream_readable(self, client: _Client) -> None:
        for _ in range(READ_BATCH):
            try:
                data = client.sock.recv(MAX_DATAGRAM)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:  # ICMP port unreachable: nothing listens on the target
                self.stats.upstream.errors += 1
                continue
            client.last_seen = self._loop.time()
            self._down.push((client.addr, data), len(data))

    def _send_up(self, item: tuple[_Client, bytes]) -> bool:
        client, data = item
        if client.sock.fileno() < 0:  # forgotten while the datagram waited
            return False
        try:
            client.sock.send(data)
        except OSError:  # buffer full, or an ICMP error of an earlier datagram
            return False
        return True

    def _send_down(self, item: tuple[SockAddr, bytes]) -> bool:
        addr, data = item
        if self._sock is None:
            return False
        try:
            self._sock.sendto(data, addr)
        except OSError:
            return False
        return True

    def _sweep(self) -> None:
        horizon = self._loop.time() - self._idle_s
        for addr, client in list(self._clients.items()):
            if client.last_seen < horizon:
                self._forget(addr)
        self._sweeper = self._loop.call_later(self._idle_s / 2, self._sweep)
