"""The manager's TCP side: one asyncio task per connection reads frames (refusing an
oversized one before reading its body), insists on HELLO first, hands requests to
core.Core and writes the answers.  Whatever a connection does wrong closes that
connection only, with one log line saying why."""

from __future__ import annotations

import asyncio
import logging
import socket
from collections.abc import Awaitable, Callable
from typing import Any, Protocol

from ...addresses import format_address
from ...tools import protocol as p
from .admission import Admission, Refused
from .core import Core, HandshakeRefused, Session, error_code

log = logging.getLogger("ln_manager")

_REQUESTS = (p.MsgType.PUBLISH, p.MsgType.SUBSCRIBE, p.MsgType.RECLAIM_PORT,
             p.MsgType.CLOSE_PORT,
             p.MsgType.TOPIC_INFO, p.MsgType.REGISTER_SERVICE, p.MsgType.UNREGISTER_SERVICE,
             p.MsgType.FIND_SERVICE, p.MsgType.SERVICE_CALLED, p.MsgType.LIST_SERVICES,
             p.MsgType.SERVICE_KEY)


# A client's host that dies or is cut off sends nothing, not even a reset: probe an idle
# connection after KEEPALIVE_IDLE s, every KEEPALIVE_INTERVAL s, and give it up after
# KEEPALIVE_COUNT unanswered probes (or data unacknowledged for USER_TIMEOUT_MS), so that
# its ports are released after about 15 s, as when a client exits.
KEEPALIVE_IDLE = 5
KEEPALIVE_INTERVAL = 2
KEEPALIVE_COUNT = 5
USER_TIMEOUT_MS = 15000


def _watch_peer(writer: asyncio.StreamWriter) -> None:
    sock = writer.get_extra_info("socket")
    if sock is None or sock.family not in (socket.AF_INET, socket.AF_INET6):
        return
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_KEEPALIVE, 1)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_KEEPIDLE, KEEPALIVE_IDLE)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_KEEPINTVL, KEEPALIVE_INTERVAL)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_KEEPCNT, KEEPALIVE_COUNT)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_USER_TIMEOUT, USER_TIMEOUT_MS)
    except (OSError, AttributeError) as exc:  # not Linux: the system's defaults
        log.debug("keepalive on a client connection: %s", exc)


class Closing(Exception):
    """The connection must be closed; the text is the reason that is logged."""


def listen_socket(host: str, port: int) -> socket.socket:
    """A listening TCP socket on the first address `host` resolves to (one socket, so that
    port 0 gives one port, the one we print)."""
    infos = socket.getaddrinfo(host or None, port, type=socket.SOCK_STREAM,
                               flags=socket.AI_PASSIVE)
    family, type_, proto, _, address = infos[0]
    sock = socket.socket(family, type_, proto)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(address)
        sock.listen(128)
        sock.setblocking(False)
    except OSError:
        sock.close()
        raise
    return sock


def _peer(writer: asyncio.StreamWriter) -> str:
    peer = writer.get_extra_info("peername")
    if isinstance(peer, tuple) and len(peer) >= 2:
        return format_address((str(peer[0]), peer[1]))
    return str(peer)


class HttpSide(Protocol):
    """What serves the HTTP connections on the clients' port (frontends/webui WebUI)."""

    def takes(self, first: bytes) -> bool:
        """Whether a connection's first bytes start an HTTP request line."""
        ...

    async def serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter,
                    first: bytes) -> None: ...


class Server:
    def __init__(self, core: Core, control: Callable[[str], Awaitable[str]] | None = None,
                 webui: HttpSide | None = None, admission: Admission | None = None) -> None:
        self.core = core
        # Who may be a client (docs/security.md); None: everyone, as without a configuration.
        self.admission = admission
        # Answers CONTROL requests (control.Control.handle_json); None: refused.
        self.control = control
        # The web UI sharing this port, given every connection that starts with an HTTP
        # request line; a client's first frame never does (docs/webui.md).
        self.webui = webui
        self._writers: set[asyncio.StreamWriter] = set()
        self._tasks: set[asyncio.Task[Any]] = set()
        self._server: asyncio.base_events.Server | None = None

    async def start(self, sock: socket.socket) -> None:
        self._server = await asyncio.start_server(self._connection, sock=sock)

    async def close(self) -> None:
        """Stop accepting, close every connection and wait for their handlers."""
        if self._server is not None:
            self._server.close()
        for writer in list(self._writers):
            writer.close()
        for task in list(self._tasks):
            task.cancel()
        if self._tasks:
            await asyncio.gather(*self._tasks, return_exceptions=True)
        if self._server is not None:
            await self._server.wait_closed()

    async def _connection(self, reader: asyncio.StreamReader,
                          writer: asyncio.StreamWriter) -> None:
        task = asyncio.current_task()
        assert task is not None
        self._tasks.add(task)
        self._writers.add(writer)
        _watch_peer(writer)
        session = Session(_peer(writer))
        log.debug("%s: connected", session.label)
        try:
            await self._serve(session, reader, writer)
        except Closing as exc:
            log.warning("%s: closing: %s", session.label, exc)
        except (ConnectionError, asyncio.CancelledError):
            pass
        except Exception:  # a bug of ours must not take the other clients down
            log.exception("%s: closing: internal error", session.label)
        finally:
            self._writers.discard(writer)
            self._tasks.discard(task)
            released = await self.core.disconnect(session)
            if session.client is not None:
                log.info("%s: disconnected, released %d port%s", session.label, released,
                         "" if released == 1 else "s")
            writer.close()

    async def _serve(self, session: Session, reader: asyncio.StreamReader,
                     writer: asyncio.StreamWriter) -> None:
        header = None
        if self.webui is not None:
            header = await self._header(reader)
            if header is None:
                return
            if self.webui.takes(header):
                await self.webui.serve(reader, writer, header)
                return
        first = await self._read(reader, header)
        if first is None:
            return  # connected and left without a word
        type_, body = first
        if type_ not in p.MESSAGES:
            raise Closing(f"unknown frame type {type_}")
        if type_ != p.MsgType.HELLO:
            raise Closing(f"first frame is type {type_}, expected HELLO ({p.MsgType.HELLO})")
        try:
            # the version first: another version's HELLO may not decode as ours
            self.core.check_version(self._hello_version(body))
            hello = self._decode(type_, body)
            assert isinstance(hello, p.Hello)
            proof = await self._admit(session, hello, reader, writer)
            welcome = self.core.hello(session, hello)
        except HandshakeRefused as exc:
            await self._send(writer, exc.reply)
            raise Closing(f"handshake refused: {exc.reply.text}") from None
        if proof is not None:
            await self._send(writer, p.AuthOk(proof.hex()))
        await self._send(writer, welcome)
        client = session.client
        assert client is not None
        admitted = session.admitted if session.admitted not in ("", "open") else ""
        log.info("%s: %s (pid %d, library %s, host %s)%s", session.label,
                 "reconnected" if hello.flags & p.HELLO_RECONNECT else "connected", client.pid,
                 client.libln_version, client.host_id or "?",
                 f", admitted by {admitted}" if admitted else "")
        while True:
            frame = await self._read(reader)
            if frame is None:
                return
            type_, body = frame
            msg = self._decode(type_, body)
            if msg.TYPE == p.MsgType.HELLO:
                raise Closing("second HELLO on one connection")
            if isinstance(msg, p.Control):
                await self._send(writer, await self._control(msg))
                continue
            if isinstance(msg, p.Log):
                await self._send(writer, self.core.log_batch(session, msg))
                continue
            if msg.TYPE not in _REQUESTS:
                raise Closing(f"unexpected {msg.TYPE.name} frame from a client")
            await self._send(writer, await self.core.request(session, msg))

    async def _admit(self, session: Session, hello: p.Hello, reader: asyncio.StreamReader,
                     writer: asyncio.StreamWriter) -> bytes | None:
        """Admission (admission.py): by the peer's credentials, else by the CHALLENGE/AUTH
        exchange; the manager's proof to send before WELCOME after the latter.
        HandshakeRefused (LN_EPERM) for a client that is not admitted."""
        if self.admission is None:
            return None
        try:
            # In a thread: the kernel query and the user database (NSS: maybe LDAP) may take
            # a while, and every other client waits on this loop.
            verdict = await asyncio.get_running_loop().run_in_executor(
                None, self.admission.judge, writer.get_extra_info("socket"))
            session.admitted = verdict.how
            if verdict.admitted:
                return None
            nonce = self.admission.challenge()
            await self._send(writer, p.Challenge(self.admission.instance, nonce.hex()))
            frame = await self._read(reader)
            if frame is None:
                raise Closing("left during admission by key")
            auth = self._decode(*frame)
            if not isinstance(auth, p.Auth):
                raise Closing(f"{auth.TYPE.name} frame instead of AUTH")
            proof, session.session_key = self.admission.verify(hello.client_name, nonce,
                                                               auth.nonce, auth.proof)
            return proof
        except Refused as exc:
            raise HandshakeRefused(p.Error(0, error_code("EPERM"), str(exc))) from None

    async def _control(self, msg: p.Control) -> p.Message:
        if self.control is None:
            return p.ControlResult(msg.request_id, '{"ok": false, "error": "this manager '
                                                   'takes no control commands"}')
        return p.ControlResult(msg.request_id, await self.control(msg.command))

    @staticmethod
    async def _header(reader: asyncio.StreamReader) -> bytes | None:
        """The length field of the next frame; None at a clean end of the stream."""
        try:
            return await reader.readexactly(p.HEADER_SIZE)
        except asyncio.IncompleteReadError as exc:
            if not exc.partial:
                return None
            raise Closing(f"truncated frame: connection closed after {len(exc.partial)} "
                          f"of {p.HEADER_SIZE} header bytes") from None

    @classmethod
    async def _read(cls, reader: asyncio.StreamReader,
                    header: bytes | None = None) -> tuple[int, bytes] | None:
        """(type, body) of the next frame (whose length field `header` may have been read
        already); None at a clean end of the stream."""
        if header is None:
            header = await cls._header(reader)
            if header is None:
                return None
        try:
            length = p.frame_length(header)
        except p.ProtocolError as exc:
            raise Closing(str(exc)) from None
        try:
            payload = await reader.readexactly(length)
        except asyncio.IncompleteReadError as exc:
            raise Closing(f"truncated frame: connection closed after {len(exc.partial)} of "
                          f"{length} bytes") from None
        return int.from_bytes(payload[:2], "little"), payload[2:]

    @staticmethod
    def _decode(type_: int, body: bytes) -> p.Message:
        cls = p.MESSAGES.get(type_)
        if cls is None:
            raise Closing(f"unknown frame type {type_}")
        if not cls.FROM_CLIENT:
            raise Closing(f"unexpected {cls.TYPE.name} frame from a client")
        try:
            return p.decode_body(cls, body)
        except p.ProtocolError as exc:
            raise Closing(str(exc)) from None

    @staticmethod
    def _hello_version(body: bytes) -> int:
        try:
            return p.hello_version(body)
        except p.ProtocolError as exc:
            raise Closing(str(exc)) from None

    @staticmethod
    async def _send(writer: asyncio.StreamWriter, msg: p.Message) -> None:
        writer.write(p.encode(msg))
        await writer.drain()
