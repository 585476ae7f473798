"""Peers for the relay tests: UDP sockets that record (and optionally echo) what they
receive, TCP servers, all on ephemeral loopback ports and the test's own event loop, and
`until`, which waits for a condition with an upper bound that is never a measurement."""

from __future__ import annotations

import asyncio
import socket
from collections.abc import AsyncIterator, Callable

import pytest

WAIT = 60.0  # seconds; only how long a test may hang before it fails
BUFFER = 4 << 20  # socket buffers asked for, so the test's own sockets drop nothing


async def until(predicate: Callable[[], object], what: str, timeout: float = WAIT) -> None:
    """Poll `predicate` on the running loop until it is true; fail naming `what`."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    while not predicate():
        if loop.time() > deadline:
            pytest.fail(f"gave up waiting for {what}")
        await asyncio.sleep(0.002)


class UdpPeer:
    """A UDP socket on 127.0.0.1 that records what it receives; with `echo` it sends every
    datagram back to where it came from."""

    def __init__(self, echo: bool = False) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        for option in (socket.SO_RCVBUF, socket.SO_SNDBUF):
            self.sock.setsockopt(socket.SOL_SOCKET, option, BUFFER)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.setblocking(False)
        self.addr: tuple[str, int] = self.sock.getsockname()
        self.echo = echo
        self.received: list[bytes] = []
        self.sources: set[tuple[str, int]] = set()
        self._loop = asyncio.get_running_loop()
        self._loop.add_reader(self.sock.fileno(), self._readable)

    def _readable(self) -> None:
        while True:
            try:
                data, source = self.sock.recvfrom(1 << 16)
            except BlockingIOError:
                return
            self.received.append(data)
            self.sources.add(source)
            if self.echo:
                self.sock.sendto(data, source)

    def send(self, data: bytes, to: tuple[str, int]) -> None:
        self.sock.sendto(data, to)

    def close(self) -> None:
        self._loop.remove_reader(self.sock.fileno())
        self.sock.close()


@pytest.fixture
async def udp_peers() -> AsyncIterator[Callable[..., UdpPeer]]:
    """Makes UdpPeers that are closed after the test."""
    peers: list[UdpPeer] = []

    def make(echo: bool = False) -> UdpPeer:
        peers.append(UdpPeer(echo))
        return peers[-1]

    yield make
    for peer in peers:
        peer.close()


def seq(index: int, size: int = 16) -> bytes:
    """A datagram carrying `index`, padded to `size` bytes with a pattern of it."""
    head = index.to_bytes(4, "big")
    return head + bytes((index + i) & 0xFF for i in range(size - 4))


def index_of(data: bytes) -> int:
    return int.from_bytes(data[:4], "big")
