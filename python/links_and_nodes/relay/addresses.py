"""Endpoints of ln_relay links: resolving and binding them when a link starts (RelayError if
that fails).  Parsing and writing `HOST:PORT` / `[V6HOST]:PORT` is links_and_nodes.addresses'."""

from __future__ import annotations

import asyncio
import socket
from typing import Any

from ..addresses import Address, format_address, parse_address

__all__ = ["Address", "RelayError", "bound_socket", "enlarge_buffers", "format_address",
           "parse_address", "resolve"]
SOCKET_BUFFER = 4 << 20  # bytes asked for; the kernel's limit applies


class RelayError(Exception):
    """A link cannot start (bad name, address in use, ...); the text says which and why."""


async def resolve(address: Address, socktype: int, *, passive: bool) -> tuple[int, Any]:
    """(family, sockaddr) of the first address getaddrinfo gives for `address`."""
    host, port = address
    loop = asyncio.get_running_loop()
    try:
        infos = await loop.getaddrinfo(host, port, type=socktype,
                                       flags=socket.AI_PASSIVE if passive else 0)
    except socket.gaierror as exc:
        raise RelayError(f"cannot resolve {host!r}: {exc.strerror}") from None
    family, _, _, _, sockaddr = infos[0]
    return family, sockaddr


def bound_socket(family: int, socktype: int, sockaddr: Any) -> socket.socket:
    """A non-blocking socket bound to `sockaddr`, with big kernel buffers where allowed
    (a relay must not be the place where datagrams are dropped by accident)."""
    sock = socket.socket(family, socktype)
    try:
        sock.setblocking(False)
        if socktype == socket.SOCK_STREAM:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        else:
            enlarge_buffers(sock)
        sock.bind(sockaddr)
    except BaseException:
        sock.close()
        raise
    return sock


def enlarge_buffers(sock: socket.socket) -> None:
    """Ask for SOCKET_BUFFER bytes of send and receive buffer; the kernel caps it at
    net.core.[rw]mem_max, which is fine."""
    for option in (socket.SO_RCVBUF, socket.SO_SNDBUF):
        try:
            sock.setsockopt(socket.SOL_SOCKET, option, SOCKET_BUFFER)
        except OSError:
            pass
