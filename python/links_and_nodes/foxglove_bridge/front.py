"""The subprotocol front of ln_foxglove: the one port clients connect to, in front of the
foxglove-sdk server.

The sdk's server accepts only the WebSocket subprotocol `foxglove.sdk.v1`; older Lichtblick,
PlotJuggler and other clients of the Foxglove WebSocket protocol ask for
`foxglove.websocket.v1`, the same protocol under its former name.  The front reads each
connection's HTTP upgrade request; if it offers `foxglove.websocket.v1` but not
`foxglove.sdk.v1`, it asks the sdk for `foxglove.sdk.v1` and names the old protocol in the
answer again.  After the handshake it copies bytes both ways untouched (the subprotocol's name
is in no frame).  It runs an asyncio loop in a thread of its own.
"""

from __future__ import annotations

import asyncio
import contextlib
import fnmatch
import threading
from collections.abc import Callable
from typing import Any

SDK = "foxglove.sdk.v1"
LEGACY = "foxglove.websocket.v1"
HEADER = b"sec-websocket-protocol"
ORIGIN = b"origin"
FORBIDDEN = (b"HTTP/1.1 403 Forbidden\r\nContent-Type: text/plain\r\nConnection: close\r\n"
             b"Content-Length: 27\r\n\r\nthis Origin is not allowed\n")
HEAD_LIMIT = 64 * 1024  # bytes of an HTTP request or response head
HANDSHAKE_TIMEOUT = 10.0  # seconds a connection may take to send its request head


def offered(head: bytes) -> list[str]:
    """The subprotocols an HTTP head names (every Sec-WebSocket-Protocol line, in order)."""
    names: list[str] = []
    for line in head.split(b"\r\n")[1:]:
        key, colon, value = line.partition(b":")
        if colon and key.strip().lower() == HEADER:
            names += [n.strip() for n in value.decode("latin-1").split(",") if n.strip()]
    return names


def origin_of(head: bytes) -> str | None:
    """The Origin header of a request head (browsers send one), or None."""
    for line in head.split(b"\r\n")[1:]:
        key, colon, value = line.partition(b":")
        if colon and key.strip().lower() == ORIGIN:
            return value.strip().decode("latin-1")
    return None


def origin_allowed(head: bytes, patterns: list[str]) -> bool:
    """Whether a request may pass the --origin patterns: without patterns, or without an
    Origin header (not a browser), yes; else only an Origin that matches one of them."""
    origin = origin_of(head)
    return not patterns or origin is None or any(fnmatch.fnmatchcase(origin, p)
                                                 for p in patterns)


def _replace_header(head: bytes, value: str) -> bytes:
    lines = head.split(b"\r\n")
    kept = [lines[0]] + [line for line in lines[1:]
                         if line.partition(b":")[0].strip().lower() != HEADER]
    # the head ends with an empty line (two after the split): the header goes before it
    while kept and kept[-1] == b"":
        kept.pop()
    kept.append(b"Sec-WebSocket-Protocol: " + value.encode("latin-1"))
    return b"\r\n".join(kept) + b"\r\n\r\n"


def rewrite_request(head: bytes) -> tuple[bytes, bool]:
    """The request head to send to the sdk, and whether the client asked for the old name
    only (then the answer must name it again)."""
    names = offered(head)
    if SDK in names or LEGACY not in names:
        return head, False
    return _replace_header(head, SDK), True


def rewrite_response(head: bytes) -> bytes:
    """The sdk's answer with the old subprotocol name, if it accepted the new one."""
    if SDK not in offered(head):
        return head
    return _replace_header(head, LEGACY)


class _Side(asyncio.Protocol):
    """One socket of a relayed connection: bytes read from it go to `peer`'s socket, and
    reading pauses while the peer's socket cannot take more (asyncio's flow control)."""

    def __init__(self) -> None:
        self.transport: Any = None
        self.peer: _Side | None = None
        self.head = bytearray()  # the HTTP head being collected, before relaying starts
        self.relaying = False

    def connection_made(self, transport: Any) -> None:
        self.transport = transport

    def data_received(self, data: bytes) -> None:
        if self.relaying:
            assert self.peer is not None
            self.peer.transport.write(data)
            return
        self.head += data
        end = self.head.find(b"\r\n\r\n")
        if end < 0:
            if len(self.head) > HEAD_LIMIT:
                self.transport.abort()
            return
        head, rest = bytes(self.head[:end + 4]), bytes(self.head[end + 4:])
        self.head.clear()
        self.on_head(head, rest)

    def on_head(self, head: bytes, rest: bytes) -> None:
        raise NotImplementedError

    def start_relaying(self, rest: bytes) -> None:
        self.relaying = True
        if rest:
            self.data_received(rest)

    def eof_received(self) -> bool:
        if self.relaying and self.peer is not None and self.peer.transport.can_write_eof():
            self.peer.transport.write_eof()
            return True  # the other direction goes on until its own end
        return False

    def connection_lost(self, exc: Exception | None) -> None:
        if self.peer is not None and not self.peer.transport.is_closing():
            self.peer.transport.close()

    def pause_writing(self) -> None:
        if self.peer is not None:
            self.peer.transport.pause_reading()

    def resume_writing(self) -> None:
        if self.peer is not None:
            self.peer.transport.resume_reading()


class _Backend(_Side):
    """The connection to the sdk's server, for one client."""

    def __init__(self, client: _Client, legacy: bool) -> None:
        super().__init__()
        self.peer = client
        self.legacy = legacy

    def on_head(self, head: bytes, rest: bytes) -> None:
        assert self.peer is not None
        self.peer.transport.write(rewrite_response(head) if self.legacy else head)
        self.start_relaying(rest)


class _Client(_Side):
    """A client's connection: its request head decides the subprotocol asked for."""

    def __init__(self, front: Front) -> None:
        super().__init__()
        self.front = front
        self.timer: asyncio.TimerHandle | None = None

    def connection_made(self, transport: Any) -> None:
        super().connection_made(transport)
        self.front.clients.add(self)
        self.timer = asyncio.get_running_loop().call_later(HANDSHAKE_TIMEOUT, transport.abort)

    def on_head(self, head: bytes, rest: bytes) -> None:
        if self.timer is not None:
            self.timer.cancel()
        if not origin_allowed(head, self.front.origins):
            self.front.refused += 1
            self.front.say(f"refused a connection from Origin {origin_of(head)!r}: no "
                           "--origin pattern allows it")
            self.transport.write(FORBIDDEN)
            self.transport.close()
            return
        self.transport.pause_reading()  # until the sdk's side is there
        head, legacy = rewrite_request(head)
        self.front.connections += 1
        self.front.legacy_connections += legacy
        task = asyncio.ensure_future(self._connect(head + rest, legacy))
        self.front.tasks.add(task)
        task.add_done_callback(self.front.tasks.discard)

    async def _connect(self, first: bytes, legacy: bool) -> None:
        loop = asyncio.get_running_loop()
        try:
            _, backend = await loop.create_connection(lambda: _Backend(self, legacy),
                                                      "127.0.0.1", self.front.backend)
        except OSError as exc:
            self.front.say(f"cannot reach the Foxglove server behind the front: {exc}")
            self.transport.write(b"HTTP/1.1 503 Service Unavailable\r\nContent-Length: 0"
                                 b"\r\nConnection: close\r\n\r\n")
            self.transport.close()
            return
        if self.transport.is_closing():
            backend.transport.close()
            return
        self.peer = backend
        backend.transport.write(first)
        self.relaying = True
        self.transport.resume_reading()

    def connection_lost(self, exc: Exception | None) -> None:
        if self.timer is not None:
            self.timer.cancel()
        self.front.clients.discard(self)
        super().connection_lost(exc)


class Front:
    """Listens on (host, port) and hands each connection to the sdk at 127.0.0.1:backend;
    `origins`: fnmatch patterns a browser's Origin must match (none: no check).  `say` gets
    one line per problem worth knowing."""

    def __init__(self, host: str, port: int, backend: int, say: Callable[[str], None],
                 origins: list[str] | None = None) -> None:
        self.host = host
        self.backend = backend
        self.say = say
        self.origins = list(origins or [])
        self.legacy_connections = 0
        self.connections = 0
        self.refused = 0  # handshakes whose Origin no pattern allowed
        self.tasks: set[asyncio.Future[None]] = set()
        self.clients: set[_Client] = set()
        self._loop = asyncio.new_event_loop()
        self._server: asyncio.Server | None = None
        started = threading.Event()
        failure: list[BaseException] = []
        self._thread = threading.Thread(target=self._run, args=(port, started, failure),
                                        daemon=True, name="foxglove front")
        self._thread.start()
        started.wait()
        if failure:
            raise failure[0]
        assert self._server is not None
        self.port = int(self._server.sockets[0].getsockname()[1])

    def _run(self, port: int, started: threading.Event, failure: list[BaseException]) -> None:
        asyncio.set_event_loop(self._loop)
        try:
            self._server = self._loop.run_until_complete(self._loop.create_server(
                lambda: _Client(self), self.host, port))
        except BaseException as exc:  # noqa: BLE001 - handed to the constructor's thread
            failure.append(exc)
            started.set()
            return
        started.set()
        self._loop.run_forever()

    def close(self) -> None:
        async def shut() -> None:
            if self._server is not None:
                self._server.close()
            for client in list(self.clients):  # Server.close leaves connections open
                client.transport.abort()
            for task in list(self.tasks):
                task.cancel()

        if self._loop.is_running():
            with contextlib.suppress(Exception):
                asyncio.run_coroutine_threadsafe(shut(), self._loop).result(timeout=5)
            self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(timeout=5)
        if not self._loop.is_running():
            self._loop.close()
