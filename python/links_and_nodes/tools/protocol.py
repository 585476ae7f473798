"""Frame codec of the client <-> manager protocol (docs/protocol.md): one dataclass per
message, `encode()` to bytes and `decode_body()` back, validating everything the document
says a frame must satisfy.  The constants, the message types and every message's fields are
read from python/links_and_nodes/wire/client.schema at import time (libln's C codec is
generated from the same file); a message's or record's class is made the first time it is
used (`p.Hello`, `MESSAGES`, decoding a frame), so that a command line that sends three
messages does not build all of them.  A leaf module: no I/O, nothing of ours imported but
the schema parser."""

from __future__ import annotations

import dataclasses
import functools
import struct
from collections.abc import Iterable
from dataclasses import dataclass
from enum import IntEnum
from typing import TYPE_CHECKING, Any, ClassVar

from ..wire import schema as _schema

SCHEMA = _schema.load(_schema.CLIENT_SCHEMA)
_CONSTS = {name: c.value for name, c in SCHEMA.consts.items()}

MAGIC: int = _CONSTS["MAGIC"]  # "LNMP" read as a little-endian u32
VERSION: int = _CONSTS["VERSION"]
HEADER_SIZE: int = _CONSTS["LENGTH_BYTES"]  # the u32 length field
MIN_LENGTH: int = _CONSTS["MIN_FRAME"]  # type only, empty body
MAX_LENGTH: int = _CONSTS["MAX_FRAME"]  # bytes after the length field: type + body
MAX_STR: int = _CONSTS["MAX_STR"]  # bytes of UTF-8 in one str field
NO_READER: int = _CONSTS["NO_READER"]  # reader_index of a publisher's PORT_OK
HELLO_RECONNECT: int = _CONSTS["HELLO_RECONNECT"]  # HELLO flags: connected before
RECLAIM_PUBLISHER: int = _CONSTS["RECLAIM_PUBLISHER"]  # RECLAIM_PORT kinds
RECLAIM_SUBSCRIBER: int = _CONSTS["RECLAIM_SUBSCRIBER"]
# Bits of PUBLISH/SUBSCRIBE `flags` (ln.h): the manager stores them with the port.
PUBLISH_WAIT_FOR_SUBSCRIBERS: int = _CONSTS["PUBLISH_WAIT_FOR_SUBSCRIBERS"]
SUBSCRIBE_UDP: int = _CONSTS["SUBSCRIBE_UDP"]
SUBSCRIBE_TCP: int = _CONSTS["SUBSCRIBE_TCP"]
# SERVICE_KEY_INFO `security` (docs/security.md, "Remote service calls").
SECURITY_NONE: int = _CONSTS["SECURITY_NONE"]
SECURITY_AUTHENTICATE: int = _CONSTS["SECURITY_AUTHENTICATE"]
SECURITY_ENCRYPT: int = _CONSTS["SECURITY_ENCRYPT"]
SERVICE_KEY_BYTES: int = _CONSTS["SERVICE_KEY_BYTES"]


class ProtocolError(Exception):
    """A malformed frame or a protocol violation; the text says exactly what is wrong."""


MsgType = IntEnum("MsgType", {e.name: e.value for e in SCHEMA.message_enum.entries})  # type: ignore[misc]

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


def _plain_kind(t: _schema.Type, where: str) -> str:
    """The codec's kind of a schema field type (this protocol uses only these), "list" for a
    list of records."""
    if t.kind == "int" and t.name in _FIXED:
        return t.name
    if t.kind == "str" and t.limit == MAX_STR and SCHEMA.str_length == "u16":
        return "str"
    if t.kind == "text":
        return "text"
    if t.kind == "list" and t.item is not None and t.item.kind == "record":
        return "list"
    raise ImportError(f"{SCHEMA.path}: {where}: {t} is not a type of the client protocol")


def _kind(t: _schema.Type, where: str) -> str | type[Record]:
    kind = _plain_kind(t, where)
    return _record(t.item.ref or "") if kind == "list" and t.item is not None else kind


# Every field's type is checked here, at import, though the classes are made later.
for _struct in (*SCHEMA.records.values(), *SCHEMA.messages.values()):
    for _field in _struct.fields:
        _plain_kind(_field.type, f"{_struct.name}.{_field.name}")


def _class(struct_: _schema.Struct, base: type[Record], namespace: dict[str, Any]) -> type[Record]:
    """The frozen dataclass of a schema record or message."""
    kinds = tuple((f.name, _kind(f.type, f"{struct_.name}.{f.name}")) for f in struct_.fields)
    fields: list[Any] = []
    for f, (_, kind) in zip(struct_.fields, kinds, strict=True):
        annotation = (f"tuple[{kind.__name__}, ...]" if isinstance(kind, type)
                      else "int" if kind in _FIXED else "str")
        fields.append((f.name, annotation) if f.default is None
                      else (f.name, annotation, dataclasses.field(default=f.default)))
    doc = struct_.doc or f"{struct_.name} (docs/protocol.md)."
    cls = dataclasses.make_dataclass(
        struct_.type_name, fields, bases=(base,), frozen=True,
        namespace={"FIELDS": kinds, "__doc__": doc, "__module__": __name__, **namespace})
    return cls


# The classes made so far, by schema name (a record's "ServiceEntry", a message's "HELLO").
_made: dict[str, type[Record]] = {}


def _record(name: str) -> type[Record]:
    cls = _made.get(name)
    if cls is None:
        cls = _made[name] = _class(SCHEMA.records[name], Record, {})
    return cls


def message_class(type_: int) -> type[Message] | None:
    """The class of message type `type_` (None if the protocol has no such type)."""
    try:
        name = MsgType(type_).name
    except ValueError:
        return None
    cls = _made.get(name)
    if cls is None:
        msg = SCHEMA.messages[name]
        cls = _made[name] = _class(msg, Message, {"TYPE": MsgType[name],
                                                  "FROM_CLIENT": msg.sender == "client"})
    return cls  # type: ignore[return-value]


# Every message class (Hello, Welcome, Error, Publish, ..., ControlResult) and record class
# (ServiceEntry) under its CamelCase name: p.Hello(...) and so on, made on first use;
# MESSAGES (type number -> class) and _RECORDS (schema name -> class) make them all.
_BY_ATTRIBUTE: dict[str, Any] = {
    **{rec.type_name: functools.partial(_record, rec.name) for rec in SCHEMA.records.values()},
    **{msg.type_name: functools.partial(message_class, MsgType[msg.name])
       for msg in SCHEMA.messages.values()},
    "MESSAGES": lambda: {MsgType[m.name]: message_class(MsgType[m.name])
                         for m in SCHEMA.messages.values()},
    "_RECORDS": lambda: {name: _record(name) for name in SCHEMA.records},
}
if TYPE_CHECKING:
    MESSAGES: dict[int, type[Message]]
    ServiceEntry: type[Record]
    ServiceList: type[Message]
    ServiceKeyInfo: type[Message]


def __getattr__(name: str) -> Any:
    make = _BY_ATTRIBUTE.get(name)
    if make is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = globals()[name] = make()  # from now on an ordinary module attribute
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_BY_ATTRIBUTE})


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


def service_list(request_id: int, entries: Iterable[Record]) -> Message:
    """The SERVICE_LIST of `entries` (in the order given): `total` counts them all, the
    list keeps as many as fit the frame limit, cutting at the end."""
    service_list_cls = message_class(MsgType.SERVICE_LIST)
    assert service_list_cls is not None
    room = MAX_LENGTH - 2 - encoded_size(service_list_cls(request_id, 0, ()))
    kept: list[Record] = []
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
    return service_list_cls(request_id, total, tuple(kept))


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
    cls = message_class(type_)
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
        return self._utf8(name, "<H", MAX_STR)

    def text(self, name: str) -> str:
        return self._utf8(name, "<I", None)

    def _utf8(self, name: str, length: str, limit: int | None) -> str:
        """A length-prefixed UTF-8 field: `str` (u16 length, at most MAX_STR) or `text`."""
        where = f"{self.type_name}.{name}"
        (count,) = self.fixed(length, f"the length of {name}")
        if limit is not None and count > limit:
            raise ProtocolError(f"{where}: str of {count} bytes, at most {limit}")
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

