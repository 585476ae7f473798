"""A small blocking client of the manager protocol for the tests, written straight from
docs/protocol.md with struct (deliberately not with the manager's own codec, so the two
check each other).  It can also send arbitrary bytes, to test how the manager copes."""

from __future__ import annotations

import os
import socket
import struct
from dataclasses import dataclass
from typing import Any

MAGIC = 0x504D4E4C
VERSION = 3
NO_READER = 0xFFFFFFFF
HELLO, WELCOME, ERROR = 1, 2, 3
PUBLISH, SUBSCRIBE, PORT_OK, CLOSE_PORT, OK, TOPIC_INFO, TOPIC_INFO_OK, RECLAIM_PORT = \
    range(10, 18)
HELLO_RECONNECT = 0x1
(REGISTER_SERVICE, UNREGISTER_SERVICE, FIND_SERVICE, SERVICE_INFO, SERVICE_CALLED,
 LIST_SERVICES, SERVICE_LIST) = range(20, 27)
TIMEOUT = 60.0  # seconds; only an upper bound for a reply that is expected to come


def s(text: str | bytes) -> bytes:
    """A `str` field: u16 byte count + bytes."""
    raw = text.encode() if isinstance(text, str) else text
    return struct.pack("<H", len(raw)) + raw


def frame(type_: int, body: bytes) -> bytes:
    return struct.pack("<IH", len(body) + 2, type_) + body


def hello_body(name: str | bytes, version: int = VERSION, magic: int = MAGIC,
               pid: int | None = None, library: str = "0.1.0",
               host_id: str | bytes = "test-host/1", flags: int = 0) -> bytes:
    return (struct.pack("<IHI", magic, version, os.getpid() if pid is None else pid)
            + s(name) + s(library) + s(host_id) + struct.pack("<I", flags))


def reclaim_body(request_id: int, kind: int, topic: str | bytes, md: str, layout_hash: int,
                 size: int, segment: str | bytes, reader_index: int = NO_READER,
                 buffers: int = 1, flags: int = 0) -> bytes:
    """RECLAIM_PORT: kind 0 publisher, 1 subscriber."""
    return (struct.pack("<IH", request_id, kind) + s(topic) + s(md)
            + struct.pack("<QIII", layout_hash, size, buffers, flags) + s(segment)
            + struct.pack("<I", reader_index))


def port_body(request_id: int, topic: str | bytes, md: str, layout_hash: int, size: int,
              buffers: int = 1, flags: int = 0) -> bytes:
    return (struct.pack("<I", request_id) + s(topic) + s(md)
            + struct.pack("<QIII", layout_hash, size, buffers, flags))


def register_service_body(request_id: int, name: str | bytes, md: str | bytes,
                          layout_hash: int, signature: str | bytes, group: str = "",
                          unix_path: str | bytes = "", tcp_host: str = "",
                          tcp_port: int = 0, host_id: str | bytes = "") -> bytes:
    return (struct.pack("<I", request_id) + s(name) + s(md) + struct.pack("<Q", layout_hash)
            + s(signature) + s(group) + s(host_id) + s(unix_path) + s(tcp_host)
            + struct.pack("<H", tcp_port))


def find_service_body(request_id: int, name: str, md: str, layout_hash: int) -> bytes:
    return struct.pack("<I", request_id) + s(name) + s(md) + struct.pack("<Q", layout_hash)


def service_called_body(request_id: int, name: str, calls: int, errors: int) -> bytes:
    return struct.pack("<I", request_id) + s(name) + struct.pack("<QQ", calls, errors)


@dataclass
class Reply:
    type: int
    fields: dict[str, Any]

    def __getattr__(self, name: str) -> Any:
        try:
            return self.fields[name]
        except KeyError:
            raise AttributeError(name) from None


class Reader:
    """Sequential reader of one body."""

    def __init__(self, body: bytes) -> None:
        self.body, self.pos = body, 0

    def take(self, fmt: str) -> Any:
        value = struct.unpack_from(fmt, self.body, self.pos)[0]
        self.pos += struct.calcsize(fmt)
        return value

    def str(self) -> str:
        count = self.take("<H")
        raw = self.body[self.pos:self.pos + count]
        assert len(raw) == count, "short str"
        self.pos += count
        return raw.decode()


_LAYOUTS = {
    WELCOME: [("version", "<H"), ("client_id", "<I"), ("client_name", "s"),
              ("instance_name", "s")],
    ERROR: [("request_id", "<I"), ("code", "<i"), ("text", "s")],
    PORT_OK: [("request_id", "<I"), ("port_id", "<I"), ("segment", "s"),
              ("reader_index", "<I")],
    OK: [("request_id", "<I")],
    TOPIC_INFO_OK: [("request_id", "<I"), ("md_name", "s"), ("layout_hash", "<Q"),
                    ("message_size", "<I"), ("publishers", "<I"), ("subscribers", "<I")],
    SERVICE_INFO: [("request_id", "<I"), ("provider", "s"), ("host_id", "s"),
                   ("unix_path", "s"), ("tcp_host", "s"), ("tcp_port", "<H"),
                   ("signature", "s")],
    SERVICE_LIST: [("request_id", "<I"), ("total", "<I"), ("count", "<I")],
}
# the layout of each of the `count` entries that follow SERVICE_LIST's fields
SERVICE_LIST_ENTRY = [("name", "s"), ("md_name", "s"), ("layout_hash", "<Q"),
                      ("provider", "s"), ("group", "s"), ("host_id", "s"), ("unix_path", "s"),
                      ("tcp_host", "s"), ("tcp_port", "<H"), ("calls", "<Q"), ("errors", "<Q")]


def _read(reader: Reader, layout: list[tuple[str, str]]) -> dict[str, Any]:
    return {name: reader.str() if fmt == "s" else reader.take(fmt) for name, fmt in layout}


def parse(type_: int, body: bytes) -> Reply:
    reader = Reader(body)
    fields = _read(reader, _LAYOUTS[type_])
    if type_ == SERVICE_LIST:
        fields["entries"] = [_read(reader, SERVICE_LIST_ENTRY) for _ in range(fields["count"])]
    assert reader.pos == len(body), f"reply type {type_} has {len(body) - reader.pos} extra bytes"
    return Reply(type_, fields)


class WireClient:
    def __init__(self, port: int, host: str = "127.0.0.1") -> None:
        self.sock = socket.create_connection((host, port), timeout=TIMEOUT)
        self._next_id = 1
        self.name = ""

    # ---- raw ------------------------------------------------------------------------------
    def send_raw(self, data: bytes) -> None:
        self.sock.sendall(data)

    def send(self, type_: int, body: bytes) -> None:
        self.send_raw(frame(type_, body))

    def _exactly(self, count: int) -> bytes:
        data = b""
        while len(data) < count:
            chunk = self.sock.recv(count - len(data))
            if not chunk:
                raise EOFError(f"connection closed after {len(data)} of {count} bytes")
            data += chunk
        return data

    def recv(self) -> Reply:
        length, type_ = struct.unpack("<IH", self._exactly(6))
        return parse(type_, self._exactly(length - 2))

    def closed_by_peer(self) -> bool:
        """Wait (at most TIMEOUT) until the manager closes; True if it did, with no data."""
        try:
            return self.sock.recv(1) == b""
        except ConnectionResetError:
            return True

    def close(self) -> None:
        self.sock.close()

    # ---- requests -------------------------------------------------------------------------
    def request_id(self) -> int:
        rid, self._next_id = self._next_id, self._next_id + 1
        return rid

    def hello(self, name: str, **kwargs: Any) -> Reply:
        self.send(HELLO, hello_body(name, **kwargs))
        reply = self.recv()
        if reply.type == WELCOME:
            self.name = reply.client_name
        return reply

    def _port(self, type_: int, topic: str, md: str, layout_hash: int, size: int,
              buffers: int = 1, flags: int = 0) -> Reply:
        rid = self.request_id()
        self.send(type_, port_body(rid, topic, md, layout_hash, size, buffers, flags))
        reply = self.recv()
        assert reply.request_id == rid
        return reply

    def publish(self, *args: Any, **kwargs: Any) -> Reply:
        return self._port(PUBLISH, *args, **kwargs)

    def subscribe(self, *args: Any, **kwargs: Any) -> Reply:
        return self._port(SUBSCRIBE, *args, **kwargs)

    def close_port(self, port_id: int) -> Reply:
        rid = self.request_id()
        self.send(CLOSE_PORT, struct.pack("<II", rid, port_id))
        reply = self.recv()
        assert reply.request_id == rid
        return reply

    def topic_info(self, topic: str) -> Reply:
        rid = self.request_id()
        self.send(TOPIC_INFO, struct.pack("<I", rid) + s(topic))
        reply = self.recv()
        assert reply.request_id == rid
        return reply

    def _call(self, type_: int, body_after_id: bytes) -> Reply:
        rid = self.request_id()
        self.send(type_, struct.pack("<I", rid) + body_after_id)
        reply = self.recv()
        assert reply.request_id == rid
        return reply

    def register_service(self, name: str, md: str, layout_hash: int, signature: str,
                         **kwargs: Any) -> Reply:
        body = register_service_body(0, name, md, layout_hash, signature, **kwargs)
        return self._call(REGISTER_SERVICE, body[4:])

    def unregister_service(self, name: str) -> Reply:
        return self._call(UNREGISTER_SERVICE, s(name))

    def find_service(self, name: str, md: str, layout_hash: int) -> Reply:
        return self._call(FIND_SERVICE, find_service_body(0, name, md, layout_hash)[4:])

    def service_called(self, name: str, calls: int, errors: int) -> Reply:
        return self._call(SERVICE_CALLED, service_called_body(0, name, calls, errors)[4:])

    def list_services(self) -> Reply:
        return self._call(LIST_SERVICES, b"")

    def __enter__(self) -> WireClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
