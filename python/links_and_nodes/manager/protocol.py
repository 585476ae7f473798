"""Frame codec of the client <-> manager protocol (docs/protocol.md): one dataclass per
message, `encode()` to bytes and `decode_body()` back, validating everything the document
says a frame must satisfy.  A leaf module: no I/O, nothing of ours imported."""

from __future__ import annotations

import struct
from dataclasses import astuple, dataclass
from enum import IntEnum
from typing import ClassVar

MAGIC = 0x504D4E4C  # "LNMP" read as a little-endian u32
VERSION = 1
HEADER_SIZE = 4  # the u32 length field
MIN_LENGTH = 2  # type only, empty body
MAX_LENGTH = 1 << 20  # bytes after the length field: type + body
MAX_STR = 1024  # bytes of UTF-8 in one str field
NO_READER = 0xFFFFFFFF  # reader_index of a publisher's PORT_OK


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
    REGISTER_SERVICE = 20
    UNREGISTER_SERVICE = 21
    FIND_SERVICE = 22
    SERVICE_INFO = 23
    SERVICE_CALLED = 24


# Field kinds: struct format of the fixed-width ones; "str" is u16 length + UTF-8.
_FIXED = {"u16": "<H", "u32": "<I", "u64": "<Q", "i32": "<i"}
_RANGES = {"u16": (0, 0xFFFF), "u32": (0, 0xFFFFFFFF), "u64": (0, (1 << 64) - 1),
           "i32": (-(1 << 31), (1 << 31) - 1)}


@dataclass(frozen=True)
class Message:
    """Base of all messages; FIELDS lists (name, kind) in wire order."""

    TYPE: ClassVar[MsgType]
    FIELDS: ClassVar[tuple[tuple[str, str], ...]]
    FROM_CLIENT: ClassVar[bool]


@dataclass(frozen=True)
class Hello(Message):
    magic: int
    version: int
    pid: int
    client_name: str
    libln_version: str
    TYPE = MsgType.HELLO
    FIELDS = (("magic", "u32"), ("version", "u16"), ("pid", "u32"),
              ("client_name", "str"), ("libln_version", "str"))
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
    unix_path: str
    tcp_host: str
    tcp_port: int
    TYPE = MsgType.REGISTER_SERVICE
    FIELDS = (("request_id", "u32"), ("name", "str"), ("md_name", "str"),
              ("layout_hash", "u64"), ("signature", "str"), ("group", "str"),
              ("unix_path", "str"), ("tcp_host", "str"), ("tcp_port", "u16"))
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
    unix_path: str
    tcp_host: str
    tcp_port: int
    signature: str
    TYPE = MsgType.SERVICE_INFO
    FIELDS = (("request_id", "u32"), ("provider", "str"), ("unix_path", "str"),
              ("tcp_host", "str"), ("tcp_port", "u16"), ("signature", "str"))
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


MESSAGES: dict[int, type[Message]] = {
    cls.TYPE: cls for cls in (Hello, Welcome, Error, Publish, Subscribe, PortOk, ClosePort,
                              Ok, TopicInfo, TopicInfoOk, RegisterService, UnregisterService,
                              FindService, ServiceInfo, ServiceCalled)}


def frame_length(header: bytes) -> int:
    """The `length` field of a frame header, checked against 2 .. 1 MiB so that a caller
    can refuse an oversized frame before reading its body."""
    if len(header) != HEADER_SIZE:
        raise ProtocolError(f"frame header has {len(header)} bytes, expected {HEADER_SIZE}")
    (length,) = struct.unpack("<I", header)
    if not MIN_LENGTH <= length <= MAX_LENGTH:
        raise ProtocolError(f"frame length {length} out of range {MIN_LENGTH}..{MAX_LENGTH}")
    return length


def encode(msg: Message) -> bytes:
    """The complete frame (length, type, body) of `msg`; ValueError if a field does not fit."""
    parts = [struct.pack("<H", msg.TYPE)]
    for (name, kind), value in zip(msg.FIELDS, astuple(msg), strict=True):
        if kind == "str":
            if not isinstance(value, str):
                raise ValueError(f"{msg.TYPE.name}.{name}: str expected, got {value!r}")
            raw = value.encode("utf-8")
            if len(raw) > MAX_STR:
                raise ValueError(f"{msg.TYPE.name}.{name}: {len(raw)} bytes, at most "
                                 f"{MAX_STR}")
            parts += [struct.pack("<H", len(raw)), raw]
        else:
            low, high = _RANGES[kind]
            if not isinstance(value, int) or not low <= value <= high:
                raise ValueError(f"{msg.TYPE.name}.{name}: {value!r} is not a {kind}")
            parts.append(struct.pack(_FIXED[kind], value))
    payload = b"".join(parts)
    if len(payload) > MAX_LENGTH:
        raise ValueError(f"{msg.TYPE.name}: frame of {len(payload)} bytes is too long")
    return struct.pack("<I", len(payload)) + payload


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


def decode_body(cls: type[Message], body: bytes) -> Message:
    """Decode the body of a `cls` frame; it must hold exactly cls's fields."""
    values: list[int | str] = []
    offset = 0
    for name, kind in cls.FIELDS:
        where = f"{cls.TYPE.name}.{name}"
        if kind == "str":
            if offset + 2 > len(body):
                raise ProtocolError(f"{cls.TYPE.name} body too short: {len(body)} bytes, "
                                    f"ends inside the length of {name}")
            (count,) = struct.unpack_from("<H", body, offset)
            offset += 2
            if count > MAX_STR:
                raise ProtocolError(f"{where}: str of {count} bytes, at most {MAX_STR}")
            if offset + count > len(body):
                raise ProtocolError(f"{cls.TYPE.name} body too short: {len(body)} bytes, "
                                    f"{name} needs {count} bytes at offset {offset}")
            raw = body[offset:offset + count]
            offset += count
            try:
                values.append(raw.decode("utf-8"))
            except UnicodeDecodeError as exc:
                raise ProtocolError(f"{where}: not valid UTF-8 (byte {exc.start})") from None
        else:
            fmt = _FIXED[kind]
            size = struct.calcsize(fmt)
            if offset + size > len(body):
                raise ProtocolError(f"{cls.TYPE.name} body too short: {len(body)} bytes, "
                                    f"ends inside {name}")
            values.append(struct.unpack_from(fmt, body, offset)[0])
            offset += size
    if offset != len(body):
        raise ProtocolError(f"{cls.TYPE.name} body too long: {len(body)} bytes, its fields "
                            f"take {offset}")
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

