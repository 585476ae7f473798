"""Frame codec of the client <-> manager protocol (docs/protocol.md): one dataclass per
message, `encode()` to bytes and `decode_body()` back, validating everything the document
says a frame must satisfy.  A leaf module: no I/O, nothing of ours imported."""

from __future__ import annotations

import struct
from collections.abc import Iterable
from dataclasses import dataclass
from enum import IntEnum
from typing import Any, ClassVar

MAGIC = 0x504D4E4C  # "LNMP" read as a little-endian u32
VERSION = 3
HEADER_SIZE = 4  # the u32 length field
MIN_LENGTH = 2  # type only, empty body
MAX_LENGTH = 1 << 20  # bytes after the length field: type + body
MAX_STR = 1024  # bytes of UTF-8 in one str field
NO_READER = 0xFFFFFFFF  # reader_index of a publisher's PORT_OK
HELLO_RECONNECT = 0x1  # HELLO flags: the client was connected to a manager of the instance
RECLAIM_PUBLISHER = 0  # RECLAIM_PORT kinds
RECLAIM_SUBSCRIBER = 1
# Bits of PUBLISH/SUBSCRIBE `flags` (ln.h): the manager stores them with the port.
PUBLISH_WAIT_FOR_SUBSCRIBERS = 0x1
SUBSCRIBE_UDP = 0x100
SUBSCRIBE_TCP = 0x200


class ProtocolError(Exception):
    """A malformed frame or a protocol violation; the text says exactly what is wrong."""


class MsgType(IntEnum):
    HELLO = 1
    WELCOME = 2
    ERROR = 3
    PUBLISH = 10
    SUBSCRIBE = 11
    PORT_OK = 12
    CLOSE_PORT = 13
    OK = 14
    TOPIC_INFO = 15
    TOPIC_INFO_OK = 16
    RECLAIM_PORT = 17
    REGISTER_SERVICE = 20
    UNREGISTER_SERVICE = 21
    FIND_SERVICE = 22
    SERVICE_INFO = 23
    SERVICE_CALLED = 24
    LIST_SERVICES = 25
    SERVICE_LIST = 26
    CONTROL = 30
    CONTROL_RESULT = 31


# Field kinds: struct format of the fixed-width ones; "str" is u16 length + UTF-8 (at most
# MAX_STR bytes); "text" is u32 length + UTF-8 (as long as the frame allows); a Record
# subclass is a list of such records: u32 count, then that many records.
_FIXED = {"u16": "<H", "u32": "<I", "u64": "<Q", "i32": "<i"}
_RANGES = {"u16": (0, 0xFFFF), "u32": (0, 0xFFFFFFFF), "u64": (0, (1 << 64) - 1),
           "i32": (-(1 << 31), (1 << 31) - 1)}


@dataclass(frozen=True)
class Record:
    """Fields in wire order: FIELDS lists (name, kind)."""

    FIELDS: ClassVar[tuple[tuple[str, str | type[Record]], ...]]


@dataclass(frozen=True)
class Message(Record):
    """Base of all messages."""

    TYPE: ClassVar[MsgType]
    FROM_CLIENT: ClassVar[bool]


@dataclass(frozen=True)
class Hello(Message):
    magic: int
    version: int
    pid: int
    client_name: str
    libln_version: str
    host_id: str  # ln_host_id() of the client's host; "" from tools without ports
    flags: int = 0  # HELLO_RECONNECT
    TYPE = MsgType.HELLO
    FIELDS = (("magic", "u32"), ("version", "u16"), ("pid", "u32"),
              ("client_name", "str"), ("libln_version", "str"), ("host_id", "str"),
              ("flags", "u32"))
    FROM_CLIENT = True


@dataclass(frozen=True)
class Welcome(Message):
    version: int
    client_id: int
    client_name: str
    instance_name: str
    TYPE = MsgType.WELCOME
    FIELDS = (("version", "u16"), ("client_id", "u32"), ("client_name", "str"),
              ("instance_name", "str"))
    FROM_CLIENT = False


@dataclass(frozen=True)
class Error(Message):
    request_id: int
    code: int
    text: str
    TYPE = MsgType.ERROR
    FIELDS = (("request_id", "u32"), ("code", "i32"), ("text", "str"))
    FROM_CLIENT = False


@dataclass(frozen=True)
class _PortRequest(Message):
    """PUBLISH and SUBSCRIBE share their body."""

    request_id: int
    topic: str
    md_name: str
    layout_hash: int
    message_size: int
    buffers: int
    flags: int
    FIELDS = (("request_id", "u32"), ("topic", "str"), ("md_name", "str"),
              ("layout_hash", "u64"), ("message_size", "u32"), ("buffers", "u32"),
              ("flags", "u32"))
    FROM_CLIENT = True


@dataclass(frozen=True)
class Publish(_PortRequest):
    TYPE = MsgType.PUBLISH


@dataclass(frozen=True)
class Subscribe(_PortRequest):
    TYPE = MsgType.SUBSCRIBE


@dataclass(frozen=True)
class ReclaimPort(Message):
    """A port a reconnecting client holds, with the ring segment it has mapped and (for a
    subscriber) its reader slot: the manager adopts them instead of making new ones."""

    request_id: int
    kind: int  # RECLAIM_PUBLISHER or RECLAIM_SUBSCRIBER
    topic: str
    md_name: str
    layout_hash: int
    message_size: int
    buffers: int
    flags: int
    segment: str
    reader_index: int
    TYPE = MsgType.RECLAIM_PORT
    FIELDS = (("request_id", "u32"), ("kind", "u16"), ("topic", "str"), ("md_name", "str"),
              ("layout_hash", "u64"), ("message_size", "u32"), ("buffers", "u32"),
              ("flags", "u32"), ("segment", "str"), ("reader_index", "u32"))
    FROM_CLIENT = True


@dataclass(frozen=True)
class PortOk(Message):
    request_id: int
    port_id: int
    segment: str
    reader_index: int
    TYPE = MsgType.PORT_OK
    FIELDS = (("request_id", "u32"), ("port_id", "u32"), ("segment", "str"),
              ("reader_index", "u32"))
    FROM_CLIENT = False


@dataclass(frozen=True)
class ClosePort(Message):
    request_id: int
    port_id: int
    TYPE = MsgType.CLOSE_PORT
    FIELDS = (("request_id", "u32"), ("port_id", "u32"))
    FROM_CLIENT = True


@dataclass(frozen=True)
class Ok(Message):
    request_id: int
    TYPE = MsgType.OK
    FIELDS = (("request_id", "u32"),)
    FROM_CLIENT = False


@dataclass(frozen=True)
class TopicInfo(Message):
    request_id: int
    topic: str
    TYPE = MsgType.TOPIC_INFO
    FIELDS = (("request_id", "u32"), ("topic", "str"))
    FROM_CLIENT = True


@dataclass(frozen=True)
class TopicInfoOk(Message):
    request_id: int
    md_name: str
    layout_hash: int
    message_size: int
    publishers: int
    subscribers: int
    TYPE = MsgType.TOPIC_INFO_OK
    FIELDS = (("request_id", "u32"), ("md_name", "str"), ("layout_hash", "u64"),
              ("message_size", "u32"), ("publishers", "u32"), ("subscribers", "u32"))
    FROM_CLIENT = False


@dataclass(frozen=True)
class RegisterService(Message):
    request_id: int
    name: str
    md_name: str
    layout_hash: int
    signature: str
    group: str
    host_id: str
    unix_path: str
    tcp_host: str
    tcp_port: int
    TYPE = MsgType.REGISTER_SERVICE
    FIELDS = (("request_id", "u32"), ("name", "str"), ("md_name", "str"),
              ("layout_hash", "u64"), ("signature", "str"), ("group", "str"),
              ("host_id", "str"), ("unix_path", "str"), ("tcp_host", "str"),
              ("tcp_port", "u16"))
    FROM_CLIENT = True


@dataclass(frozen=True)
class UnregisterService(Message):
    request_id: int
    name: str
    TYPE = MsgType.UNREGISTER_SERVICE
    FIELDS = (("request_id", "u32"), ("name", "str"))
    FROM_CLIENT = True


@dataclass(frozen=True)
class FindService(Message):
    request_id: int
    name: str
    md_name: str
    layout_hash: int
    TYPE = MsgType.FIND_SERVICE
    FIELDS = (("request_id", "u32"), ("name", "str"), ("md_name", "str"),
              ("layout_hash", "u64"))
    FROM_CLIENT = True


@dataclass(frozen=True)
class ServiceInfo(Message):
    request_id: int
    provider: str
    host_id: str
    unix_path: str
    tcp_host: str
    tcp_port: int
    signature: str
    TYPE = MsgType.SERVICE_INFO
    FIELDS = (("request_id", "u32"), ("provider", "str"), ("host_id", "str"),
              ("unix_path", "str"), ("tcp_host", "str"), ("tcp_port", "u16"),
              ("signature", "str"))
    FROM_CLIENT = False


@dataclass(frozen=True)
class ServiceCalled(Message):
    request_id: int
    name: str
    calls: int
    errors: int
    TYPE = MsgType.SERVICE_CALLED
    FIELDS = (("request_id", "u32"), ("name", "str"), ("calls", "u64"), ("errors", "u64"))
    FROM_CLIENT = True


@dataclass(frozen=True)
class ListServices(Message):
    request_id: int
    TYPE = MsgType.LIST_SERVICES
    FIELDS = (("request_id", "u32"),)
    FROM_CLIENT = True


@dataclass(frozen=True)
class ServiceEntry(Record):
    """One service of a SERVICE_LIST."""

    name: str
    md_name: str
    layout_hash: int
    provider: str
    group: str
    host_id: str
    unix_path: str
    tcp_host: str
    tcp_port: int
    calls: int
    errors: int
    FIELDS = (("name", "str"), ("md_name", "str"), ("layout_hash", "u64"),
              ("provider", "str"), ("group", "str"), ("host_id", "str"), ("unix_path", "str"),
              ("tcp_host", "str"), ("tcp_port", "u16"), ("calls", "u64"), ("errors", "u64"))


@dataclass(frozen=True)
class ServiceList(Message):
    """`total` services exist; `entries` are the first of them (by name) that fit a frame."""

    request_id: int
    total: int
    entries: tuple[ServiceEntry, ...]
    TYPE = MsgType.SERVICE_LIST
    FIELDS = (("request_id", "u32"), ("total", "u32"), ("entries", ServiceEntry))
    FROM_CLIENT = False


@dataclass(frozen=True)
class Control(Message):
    """A command for the process scheduler, as a JSON object (docs/process_management.md,
    "Control requests")."""

    request_id: int
    command: str
    TYPE = MsgType.CONTROL
    FIELDS = (("request_id", "u32"), ("command", "text"))
    FROM_CLIENT = True


@dataclass(frozen=True)
class ControlResult(Message):
    """The JSON answer to a CONTROL: {"ok": true, ...} or {"ok": false, "error": TEXT}."""

    request_id: int
    result: str
    TYPE = MsgType.CONTROL_RESULT
    FIELDS = (("request_id", "u32"), ("result", "text"))
    FROM_CLIENT = False


MESSAGES: dict[int, type[Message]] = {
    cls.TYPE: cls for cls in (Hello, Welcome, Error, Publish, Subscribe, ReclaimPort, PortOk,
                              ClosePort,
                              Ok, TopicInfo, TopicInfoOk, RegisterService, UnregisterService,
                              FindService, ServiceInfo, ServiceCalled, ListServices,
                              ServiceList, Control, ControlResult)}


def frame_length(header: bytes) -> int:
    """The `length` field of a frame header, checked against 2 .. 1 MiB so that a caller
    can refuse an oversized frame before reading its body."""
    if len(header) != HEADER_SIZE:
        raise ProtocolError(f"frame header has {len(header)} bytes, expected {HEADER_SIZE}")
    (length,) = struct.unpack("<I", header)
    if not MIN_LENGTH <= length <= MAX_LENGTH:
        raise ProtocolError(f"frame length {length} out of range {MIN_LENGTH}..{MAX_LENGTH}")
    return length


def _encode_fields(record: Record, where: str) -> list[bytes]:
    parts = []
    for name, kind in record.FIELDS:
        value = getattr(record, name)
        field = f"{where}.{name}"
        if isinstance(kind, type):
            if not isinstance(value, tuple) or not all(isinstance(v, kind) for v in value):
                raise ValueError(f"{field}: tuple of {kind.__name__} expected, got {value!r}")
            if len(value) > 0xFFFFFFFF:
                raise ValueError(f"{field}: {len(value)} entries do not fit a u32 count")
            parts.append(struct.pack("<I", len(value)))
            for index, item in enumerate(value):
                parts += _encode_fields(item, f"{field}[{index}]")
        elif kind == "str":
            if not isinstance(value, str):
                raise ValueError(f"{field}: str expected, got {value!r}")
            raw = value.encode("utf-8")
            if len(raw) > MAX_STR:
                raise ValueError(f"{field}: {len(raw)} bytes, at most {MAX_STR}")
            parts += [struct.pack("<H", len(raw)), raw]
        elif kind == "text":
            if not isinstance(value, str):
                raise ValueError(f"{field}: str expected, got {value!r}")
            raw = value.encode("utf-8")
            parts += [struct.pack("<I", len(raw)), raw]
        else:
            low, high = _RANGES[kind]
            if not isinstance(value, int) or not low <= value <= high:
                raise ValueError(f"{field}: {value!r} is not a {kind}")
            parts.append(struct.pack(_FIXED[kind], value))
    return parts


def encode(msg: Message) -> bytes:
    """The complete frame (length, type, body) of `msg`; ValueError if a field does not fit."""
    payload = b"".join([struct.pack("<H", msg.TYPE), *_encode_fields(msg, msg.TYPE.name)])
    if len(payload) > MAX_LENGTH:
        raise ValueError(f"{msg.TYPE.name}: frame of {len(payload)} bytes is too long")
    return struct.pack("<I", len(payload)) + payload


def encoded_size(record: Record) -> int:
    """Bytes of `record`'s fields on the wire (a message's body, without length and type)."""
    return sum(len(part) for part in _encode_fields(record, type(record).__name__))


def service_list(request_id: int, entries: Iterable[ServiceEntry]) -> ServiceList:
    """The SERVICE_LIST of `entries` (in the order given): `total` counts them all, the
    list keeps as many as fit the frame limit, cutting at the end."""
    room = MAX_LENGTH - 2 - encoded_size(ServiceList(request_id, 0, ()))
    kept: list[ServiceEntry] = []
    total = 0
    full = False
    for entry in entries:
        total += 1
        if not full:
            size = encoded_size(entry)
            full = size > room
            if not full:
                kept.append(entry)
                room -= size
    return ServiceList(request_id, total, tuple(kept))


def decode_frame(frame: bytes) -> Message:
    """Decode one complete frame (length field included); the length must match exactly."""
    length = frame_length(frame[:HEADER_SIZE])
    if len(frame) - HEADER_SIZE != length:
        raise ProtocolError(f"frame length field says {length} bytes, "
                            f"{len(frame) - HEADER_SIZE} follow")
    return decode_payload(frame[HEADER_SIZE:])


def decode_payload(payload: bytes) -> Message:
    """Decode type + body (everything after the length field)."""
    if len(payload) < MIN_LENGTH:
        raise ProtocolError(f"frame of {len(payload)} bytes has no type")
    (type_,) = struct.unpack_from("<H", payload)
    cls = MESSAGES.get(type_)
    if cls is None:
        raise ProtocolError(f"unknown frame type {type_}")
    return decode_body(cls, payload[2:])


class _Reader:
    """Reads the fields of one body in order; errors name the message type and field."""

    def __init__(self, type_name: str, body: bytes) -> None:
        self.type_name = type_name
        self.body = body
        self.offset = 0

    def too_short(self, detail: str) -> ProtocolError:
        return ProtocolError(f"{self.type_name} body too short: {len(self.body)} bytes, "
                             f"{detail}")

    def fields(self, cls: type[Record], prefix: str = "") -> list[Any]:
        values: list[Any] = []
        for field_name, kind in cls.FIELDS:
            name = prefix + field_name
            if isinstance(kind, type):
                (count,) = self.fixed("<I", f"the count of {name}")
                values.append(tuple(kind(*self.fields(kind, f"{name}[{index}]."))
                                    for index in range(count)))
            elif kind == "str":
                values.append(self.str(name))
            elif kind == "text":
                values.append(self.text(name))
            else:
                (value,) = self.fixed(_FIXED[kind], name)
                values.append(value)
        return values

    def fixed(self, fmt: str, what: str) -> tuple[Any, ...]:
        size = struct.calcsize(fmt)
        if self.offset + size > len(self.body):
            raise self.too_short(f"ends inside {what}")
        values = struct.unpack_from(fmt, self.body, self.offset)
        self.offset += size
        return values

    def str(self, name: str) -> str:
        where = f"{self.type_name}.{name}"
        (count,) = self.fixed("<H", f"the length of {name}")
        if count > MAX_STR:
            raise ProtocolError(f"{where}: str of {count} bytes, at most {MAX_STR}")
        if self.offset + count > len(self.body):
            raise self.too_short(f"{name} needs {count} bytes at offset {self.offset}")
        raw = self.body[self.offset:self.offset + count]
        self.offset += count
        try:
            return raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise ProtocolError(f"{where}: not valid UTF-8 (byte {exc.start})") from None


    def text(self, name: str) -> str:
        where = f"{self.type_name}.{name}"
        (count,) = self.fixed("<I", f"the length of {name}")
        if self.offset + count > len(self.body):
            raise self.too_short(f"{name} needs {count} bytes at offset {self.offset}")
        raw = self.body[self.offset:self.offset + count]
        self.offset += count
        try:
            return raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise ProtocolError(f"{where}: not valid UTF-8 (byte {exc.start})") from None


def decode_body(cls: type[Message], body: bytes) -> Message:
    """Decode the body of a `cls` frame; it must hold exactly cls's fields."""
    reader = _Reader(cls.TYPE.name, body)
    values = reader.fields(cls)
    if reader.offset != len(body):
        raise ProtocolError(f"{cls.TYPE.name} body too long: {len(body)} bytes, its fields "
                            f"take {reader.offset}")
    if cls.FROM_CLIENT and cls.FIELDS[0][0] == "request_id" and values[0] == 0:
        raise ProtocolError(f"{cls.TYPE.name} with request id 0 (must be non-zero)")
    return cls(*values)


def hello_version(body: bytes) -> int:
    """Magic check and protocol version of a HELLO body.

    Only magic and version are read, so a client of another protocol version (whose HELLO
    may carry other fields) still gets the LN_EVERSION answer rather than a closed socket."""
    if len(body) < 6:
        raise ProtocolError(f"HELLO body too short: {len(body)} bytes, ends inside "
                            "magic/version")
    magic, version = struct.unpack_from("<IH", body)
    if magic != MAGIC:
        raise ProtocolError(f"HELLO with wrong magic 0x{magic:08x}, expected 0x{MAGIC:08x}")
    return version

