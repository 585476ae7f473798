"""Endpoints of ln_relay links: parsing `HOST:PORT` / `[V6HOST]:PORT`, the text form used
in its output, and resolving and binding them when a link starts (RelayError if that
fails)."""

from __future__ import annotations

import asyncio
import socket
from typing import Any

Address = tuple[str, int]
SOCKET_BUFFER = 4 << 20  # bytes asked for; the kernel's limit applies


def parse_address(text: str, *, allow_port_zero: bool = False) -> Address:
    """(host, port) of `HOST:PORT` or `[V6HOST]:PORT`; ValueError saying what is wrong.
    Port 0 (the kernel picks one) only where `allow_port_zero`, i.e. for LISTEN."""
    host, colon, port = text.rpartition(":")
    if host.startswith("[") and host.endswith("]") and len(host) >= 2:
        host = host[1:-1]
        if not host or ":" not in host:
            raise ValueError(f"bad address {text!r}: brackets are for IPv6 addresses")
    elif ":" in host:
        raise ValueError(f"bad address {text!r}: an IPv6 address needs brackets, "
                         "e.g. [::1]:5000")
    if not colon or not host:
        raise ValueError(f"bad address {text!r}: expected HOST:PORT or [V6HOST]:PORT")
    low = 0 if allow_port_zero else 1
    if not port.isascii() or not port.isdigit() or not low <= int(port) <= 65535:
        raise ValueError(f"bad address {text!r}: the port must be a number "
                         f"{low}..65535")
    return host, int(port)


def format_address(address: Address) -> str:
    """`host:port`, with brackets around an IPv6 host."""
    host, port = address
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


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
