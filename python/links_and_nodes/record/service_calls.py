"""Receiving copies of service calls (docs/services.md, "Recording calls") and their MCAP form
(docs/recording.md, "Service calls").

`ServiceCallTap` follows the manager's service list and taps every provider whose service name
matches one of its patterns: it connects to the provider's socket with TAP and from then on
receives a CALL frame for each completed call.  `encode_call`/`decode_call` are the message
encoding of a recorded call; `ServiceRecording` writes a tap's calls beside ln_record's topics.
"""

from __future__ import annotations

import contextlib
import os
import queue
import re
import selectors
import socket
import struct
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

from ..addresses import parse_manager_address
from ..tools import client_key
from ..tools import protocol as p
from ..tools.framing import receive

MESSAGE_ENCODING = "ln-service-call"  # the channel's message encoding (encode_call)
SIGNATURE_ENCODING = "ln-service-signature"  # schema: the md's "request|response" signature
CALL_VERSION = 1
STATUS_OK, STATUS_ERROR = 0, 1
POLL_INTERVAL = 0.2  # seconds between looks at the manager's service list
CONNECT_TIMEOUT = 2.0

# service wire (libln/src/svc_wire.h)
_SVC_MAGIC, _SVC_VERSION = 0x56534E4C, 1
_ERROR, _TAP, _TAPPED, _CALL = 5, 6, 7, 8
_FRAME = struct.Struct("<IH")
_CALL_HEAD = struct.Struct("<QQQi")  # request time, duration, dropped, code
_RECORD = struct.Struct("<BBiQQHHII")  # see encode_call


@dataclass(frozen=True)
class ServiceCall:
    """One completed call of a recorded service.  `response` is the response in the service's
    wire form when status is STATUS_OK; `error` the error text (and `code` its LN_E* code)
    when it is STATUS_ERROR."""

    service: str
    md_name: str
    layout_hash: int
    caller: str
    provider: str
    request_time_ns: int  # CLOCK_REALTIME when the provider received the request
    duration_ns: int  # until the provider had its answer
    request: bytes
    response: bytes = b""
    error: str = ""
    code: int = 0
    signature: str = ""

    @property
    def status(self) -> int:
        return STATUS_OK if self.code == 0 else STATUS_ERROR


class CallFormatError(ValueError):
    """A recorded call that does not decode; the text names the byte offset."""


def encode_call(call: ServiceCall) -> bytes:
    """The message of one call on a service channel: a 34-byte header (u8 version, u8 status,
    i32 code, u64 request_time_ns, u64 duration_ns, u16 caller bytes, u16 provider bytes,
    u32 request bytes, u32 answer bytes; little endian), then caller, provider (UTF-8), the
    request (wire form) and the answer: the response (wire form) or the error text (UTF-8)."""
    caller, provider = call.caller.encode(), call.provider.encode()
    answer = call.response if call.code == 0 else call.error.encode("utf-8", "replace")
    return b"".join((
        _RECORD.pack(CALL_VERSION, call.status, call.code, call.request_time_ns,
                     call.duration_ns, len(caller), len(provider), len(call.request),
                     len(answer)),
        caller, provider, call.request, answer))


def decode_call(data: bytes | memoryview, service: str = "", md_name: str = "",
                layout_hash: int = 0) -> ServiceCall:
    """The call of one message of a service channel (the channel gives service, md name and
    layout hash); CallFormatError naming the byte offset if it is not one."""
    data = bytes(data)
    if len(data) < _RECORD.size:
        raise CallFormatError(f"a call record of {len(data)} bytes is shorter than its "
                              f"{_RECORD.size}-byte header")
    version, status, code, t_ns, dur, nc, np_, nreq, nans = _RECORD.unpack_from(data)
    if version != CALL_VERSION:
        raise CallFormatError(f"byte 0: call record version {version}, expected {CALL_VERSION}")
    if status not in (STATUS_OK, STATUS_ERROR) or (status == STATUS_OK) != (code == 0):
        raise CallFormatError(f"byte 1: status {status} does not go with code {code}")
    end = _RECORD.size + nc + np_ + nreq + nans
    if end != len(data):
        raise CallFormatError(f"byte {_RECORD.size}: the header announces {end} bytes, the "
                              f"record has {len(data)}")
    at = _RECORD.size
    fields = []
    for n in (nc, np_, nreq, nans):
        fields.append(data[at:at + n])
        at += n
    try:
        caller, provider = fields[0].decode(), fields[1].decode()
        error = fields[3].decode() if status == STATUS_ERROR else ""
    except UnicodeDecodeError as exc:
        raise CallFormatError(f"a name or error text is not UTF-8: {exc}") from None
    return ServiceCall(service, md_name, layout_hash, caller, provider, t_ns, dur, fields[2],
                       fields[3] if status == STATUS_OK else b"", error, code)


def channel_fields(service: str, md_name: str, layout_hash: int, signature: str
                   ) -> dict[str, Any]:
    """McapWriter.add_channel's keywords for the calls of one service."""
    return {"schema_name": md_name, "schema_encoding": SIGNATURE_ENCODING,
            "schema_data": signature.encode(), "message_encoding": MESSAGE_ENCODING,
            "metadata": {"kind": "service", "md_name": md_name,
                         "layout_hash": f"{layout_hash:016x}", "message_size": "0",
                         "signature": signature}}


# ---- the tap ----------------------------------------------------------------------------


def _str(text: str) -> bytes:
    raw = text.encode()
    return struct.pack("<H", len(raw)) + raw


class _Frames:
    """Frames out of a byte stream."""

    def __init__(self) -> None:
        self.buf = bytearray()

    def feed(self, data: bytes) -> Iterator[tuple[int, bytes]]:
        self.buf += data
        while len(self.buf) >= _FRAME.size:
            length, kind = _FRAME.unpack_from(self.buf)
            if length < 2:
                raise ValueError(f"frame length {length}")
            if len(self.buf) < 4 + length:
                return
            body = bytes(self.buf[_FRAME.size:4 + length])
            del self.buf[:4 + length]
            yield kind, body


def _read_str(body: bytes, at: int) -> tuple[str, int]:
    (n,) = struct.unpack_from("<H", body, at)
    return body[at + 2:at + 2 + n].decode(), at + 2 + n


@dataclass
class _Tapped:
    """A provider connection of the tap."""

    service: str
    md_name: str
    layout_hash: int
    provider: str
    signature: str
    sock: socket.socket
    frames: _Frames
    dropped: int = 0


def _call_of(t: _Tapped, body: bytes) -> ServiceCall:
    t_ns, dur, dropped, code = _CALL_HEAD.unpack_from(body)
    caller, at = _read_str(body, _CALL_HEAD.size)
    (n,) = struct.unpack_from("<I", body, at)
    request = body[at + 4:at + 4 + n]
    at += 4 + n
    (m,) = struct.unpack_from("<I", body, at)
    answer = body[at + 4:at + 4 + m]
    if at + 4 + m != len(body) or len(answer) != m or len(request) != n:
        raise ValueError("CALL frame of the wrong length")
    t.dropped = dropped
    if code == 0:
        return ServiceCall(t.service, t.md_name, t.layout_hash, caller, t.provider, t_ns, dur,
                           request, answer, "", 0, t.signature)
    return ServiceCall(t.service, t.md_name, t.layout_hash, caller, t.provider, t_ns, dur,
                       request, b"", answer.decode("utf-8", "replace"), code, t.signature)


def connect_provider(entry: Any, local_host: str) -> socket.socket:
    """A connection to the provider of `entry` (a SERVICE_LIST entry): its Unix socket on
    this host, else TCP."""
    if entry.unix_path and entry.host_id == local_host:
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        sock.settimeout(CONNECT_TIMEOUT)
        try:
            sock.connect(entry.unix_path)
            return sock
        except OSError:
            sock.close()
            if not entry.tcp_port:
                raise
    sock = socket.create_connection((entry.tcp_host, entry.tcp_port), timeout=CONNECT_TIMEOUT)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return sock


class ServiceDirectory:
    """The manager's service list over one connection of its own (reopened after a failure):
    SERVICE_LIST entries with every provider's addresses (docs/protocol.md)."""

    def __init__(self, manager: tuple[str, int], client_name: str) -> None:
        self.manager = manager
        self.client_name = client_name
        self._sock: socket.socket | None = None

    def services(self) -> tuple[Any, ...]:
        """The entries; OSError / ConnectionError if the manager cannot be asked."""
        try:
            if self._sock is None:
                self._sock = self._hello()
            self._sock.sendall(p.encode(p.ListServices(1)))
            reply = receive(self._sock, ConnectionError)
        except BaseException:
            self.close()
            raise
        if not isinstance(reply, p.ServiceList):
            self.close()
            raise ConnectionError(f"the manager answered LIST_SERVICES with {reply.TYPE.name}")
        return tuple(reply.entries)

    def _hello(self) -> socket.socket:
        sock = socket.create_connection(self.manager, timeout=CONNECT_TIMEOUT)
        try:
            welcome = client_key.greet(sock, self.client_name, ConnectionError)
            if not isinstance(welcome, p.Welcome):
                raise ConnectionError("the manager refused the connection"
                                      + (f": {welcome.text}" if isinstance(welcome, p.Error)
                                         else ""))
        except BaseException:
            sock.close()
            raise
        return sock

    def close(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None


def local_host_id() -> str:
    try:
        from .. import _adminlib

        return _adminlib.host_id()
    except Exception:  # noqa: BLE001 - no libln_admin here: TCP always works
        return os.environ.get("LN_HOST_ID", "")


class ServiceCallTap:
    """Receives a copy of every completed call of the services whose names match one of
    `patterns` (re.fullmatch), also of services and providers that appear later (found
    within `poll` seconds).  Iterate it, or get(timeout), for ServiceCall records.  It holds
    at most `queue_size` calls: while that is full it stops reading, and the providers drop
    (and count) the calls that do not fit their own bounded queues (`drops`)."""

    def __init__(self, manager: str, patterns: list[str], name: str = "ln_record",
                 poll: float = POLL_INTERVAL, queue_size: int = 10000,
                 on_attach: Callable[[str, str], None] | None = None) -> None:
        self.manager = parse_manager_address(manager)
        self.patterns = [re.compile(x) for x in patterns]
        self.name = name
        self.poll = poll
        self.on_attach = on_attach
        self.calls: queue.Queue[ServiceCall] = queue.Queue(queue_size)
        self.tapped: dict[str, _Tapped] = {}  # by service name: the live connections
        self._keys: dict[tuple[Any, ...], _Tapped] = {}
        self._dropped_closed = 0
        self._sel = selectors.DefaultSelector()
        self._stop = threading.Event()
        self._draining = threading.Event()
        self._drain = 0.0
        self.directory = ServiceDirectory(self.manager, f"{name}.services")
        self._host = local_host_id()
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._run, daemon=True, name="ln service tap")
        self._thread.start()

    def wanted(self, service: str) -> bool:
        return any(r.fullmatch(service) for r in self.patterns)

    @property
    def drops(self) -> int:
        """Calls the providers dropped because this tap was too slow (as far as reported)."""
        with self._lock:
            return self._dropped_closed + sum(t.dropped for t in self._keys.values())

    def get(self, timeout: float | None = None) -> ServiceCall | None:
        try:
            return self.calls.get(timeout=timeout)
        except queue.Empty:
            return None

    def __iter__(self) -> Iterator[ServiceCall]:
        while not (self._stop.is_set() and self.calls.empty()):
            call = self.get(0.1)
            if call is not None:
                yield call

    def close(self, drain: float = 0.0) -> None:
        """Stop tapping; with `drain` > 0 first take what the providers still send, until
        nothing came for `drain` seconds (calls that completed just before)."""
        self._drain = drain
        if drain <= 0:
            self._stop.set()  # also ends a put into a full queue
        self._draining.set()
        self._thread.join()
        self._stop.set()
        for t in list(self._keys.values()):
            self._drop(t)
        self.directory.close()
        self._sel.close()

    def __enter__(self) -> ServiceCallTap:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ---- the thread ----

    def _run(self) -> None:
        next_poll = 0.0
        while not self._draining.is_set():
            now = time.monotonic()
            if now >= next_poll:
                self._follow_listing()
                next_poll = now + self.poll
            for key, _ in self._sel.select(timeout=max(0.0, min(0.1, next_poll - now))):
                self._readable(key.data)
        while self._drain > 0 and self._keys:
            events = self._sel.select(timeout=self._drain)
            if not events:
                break
            for key, _ in events:
                self._readable(key.data)

    def _follow_listing(self) -> None:
        try:
            entries = self.directory.services()
        except (OSError, ConnectionError):
            return
        for e in entries:
            key = (e.name, e.provider, e.unix_path, e.tcp_host, e.tcp_port, e.layout_hash)
            if key in self._keys or not self.wanted(e.name):
                continue
            with contextlib.suppress(OSError, ValueError, struct.error):
                self._attach(key, e)

    def _attach(self, key: tuple[Any, ...], e: Any) -> None:
        sock = connect_provider(e, self._host)
        try:
            sock.sendall(self._tap_frame(e.name))
            frames = _Frames()
            kind, body = self._first_frame(sock, frames)
            if kind != _TAPPED:
                raise ValueError(f"provider answered TAP with frame type {kind}")
            md_name, at = _read_str(body, 0)
            (layout_hash,) = struct.unpack_from("<Q", body, at)
            provider, at = _read_str(body, at + 8)
            signature, at = _read_str(body, at)
        except BaseException:
            sock.close()
            raise
        sock.setblocking(False)
        t = _Tapped(e.name, md_name, layout_hash, provider, signature, sock, frames)
        with self._lock:
            self._keys[key] = t
        self.tapped[e.name] = t
        self._sel.register(sock, selectors.EVENT_READ, t)
        if self.on_attach is not None:
            self.on_attach(e.name, provider)
        if frames.buf:  # calls right behind TAPPED
            self._readable(t, b"")

    def _tap_frame(self, service: str) -> bytes:
        body = struct.pack("<IH", _SVC_MAGIC, _SVC_VERSION) + _str(service) + _str(self.name)
        return _FRAME.pack(len(body) + 2, _TAP) + body

    @staticmethod
    def _first_frame(sock: socket.socket, frames: _Frames) -> tuple[int, bytes]:
        while True:
            chunk = sock.recv(1 << 16)
            if not chunk:
                raise ValueError("the provider closed the connection")
            for kind, body in frames.feed(chunk):
                return kind, body

    def _readable(self, t: _Tapped, data: bytes | None = None) -> None:
        try:
            if data is None:
                data = t.sock.recv(1 << 20)
                if not data:
                    raise ConnectionError("closed")
            for kind, body in t.frames.feed(data):
                if kind != _CALL:
                    raise ValueError(f"unexpected frame type {kind}")
                call = _call_of(t, body)
                while not self._stop.is_set():
                    try:
                        self.calls.put(call, timeout=0.1)
                        break
                    except queue.Full:
                        continue
        except BlockingIOError:
            return
        except (OSError, ValueError, struct.error):
            self._drop(t)

    def _drop(self, t: _Tapped) -> None:
        with contextlib.suppress(KeyError, ValueError):
            self._sel.unregister(t.sock)
        t.sock.close()
        with self._lock:
            for key, other in list(self._keys.items()):
                if other is t:
                    del self._keys[key]
                    self._dropped_closed += t.dropped
        if self.tapped.get(t.service) is t:
            del self.tapped[t.service]
