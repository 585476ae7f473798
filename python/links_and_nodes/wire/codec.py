"""The Python codec of a wire schema, built from the schema file at import time (no packing
code per message; a message's encoder and decoder are made when it is first used):
`DAEMON.encode("SPAWN", spec) -> bytes`, `DAEMON.decode("SPAWNED", payload) -> dict`.

Values: a message or record is a dict (encode also takes any object with the fields as
attributes); a missing field takes its schema default, else zero / "" / b"" / [].  A flags
field contributes one bool per bit, named like the bit, at its struct's level.  Enums
decode to the IntEnum named like the schema's enum (`codec.enums["Stream"]`) and encode
from an int or an entry name; `str` encodes str (UTF-8, surrogateescape) or bytes and
decodes to str (invalid UTF-8 replaced); `bytes` and `tail` are bytes.  Anything that does
not fit (a number out of range, a string over its limit, a short payload, bytes left over, a
bool not 0 or 1, an unknown enum value or flag bit) raises WireError.
"""

from __future__ import annotations

import enum
import struct
from collections.abc import Callable, Mapping
from typing import Any

from . import schema as sch

_FORMATS = {"u8": "<B", "u16": "<H", "u32": "<I", "u64": "<Q", "i32": "<i", "i64": "<q",
            "f64": "<d", "bool": "<B"}
_PACKERS = {k: struct.Struct(v) for k, v in _FORMATS.items()}
_MISSING = object()


class WireError(ValueError, struct.error):
    """A value that does not fit the schema, or a payload that is not what it should be
    (also a struct.error, which hand-written packing raised before)."""


class _Buf:
    __slots__ = ("data", "pos")

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.pos = 0

    def take(self, n: int) -> bytes:
        if n > len(self.data) - self.pos:
            raise WireError("short payload")
        out = self.data[self.pos:self.pos + n]
        self.pos += n
        return bytes(out)

    def scalar(self, name: str) -> Any:
        p = _PACKERS[name]
        if p.size > len(self.data) - self.pos:
            raise WireError("short payload")
        (v,) = p.unpack_from(self.data, self.pos)
        self.pos += p.size
        return v


def _get(obj: Any, name: str) -> Any:
    if isinstance(obj, Mapping):
        return obj.get(name, _MISSING)
    return getattr(obj, name, _MISSING)


def _to_bytes(value: Any) -> bytes:
    if isinstance(value, str):
        # surrogateescape: what os.environ, sys.argv and os.fsdecode make of bytes that are
        # not UTF-8 goes back as those bytes
        return value.encode(errors="surrogateescape")
    if isinstance(value, (bytes, bytearray, memoryview)):
        return bytes(value)
    raise WireError(f"expected str or bytes, got {type(value).__name__}")


def encode_str(value: str | bytes) -> bytes:
    """A `str` of a protocol whose str_length is u32 (the daemon's): u32 length and the
    bytes, without a limit; for payloads built by hand (tests of malformed requests)."""
    b = _to_bytes(value)
    return _PACKERS["u32"].pack(len(b)) + b


Encoder = Callable[[list[bytes], Any, str], None]
Decoder = Callable[[_Buf, dict[str, Any]], None]
ValueDecoder = Callable[[_Buf], Any]  # one value of a type (a field's is a Decoder)


class Codec:
    """Encoder and decoder of every message of one schema."""

    def __init__(self, schema: sch.Schema) -> None:
        self.schema = schema
        self.consts: dict[str, int | str] = {c.name: c.value for c in schema.consts.values()}
        self.enums: dict[str, type[enum.IntEnum]] = {
            e.name: enum.IntEnum(e.name, [(x.name, x.value) for x in e.entries])
            for e in schema.enums.values() if e.kind == "enum"}
        self.msg = self.enums[schema.message_enum.name]
        self._structs = {s.name: s for s in [*schema.records.values(),
                                             *schema.messages.values()]}
        self._coders: dict[str, tuple[Encoder, Decoder]] = {}  # made on first use

    # -- public --

    def encode(self, message: str, obj: Any = None) -> bytes:
        """The payload of `message` (a message name like "SPAWN") with the values of `obj`."""
        if message not in self.schema.messages:
            raise WireError(f"no message {message}")
        out: list[bytes] = []
        self._coder(message)[0](out, {} if obj is None else obj, message)
        return b"".join(out)

    def decode(self, message: str, data: bytes) -> dict[str, Any]:
        """The fields of a `message` payload; WireError if it is malformed."""
        if message not in self.schema.messages:
            raise WireError(f"no message {message}")
        buf = _Buf(memoryview(data) if not isinstance(data, bytes) else data)
        out: dict[str, Any] = {}
        self._coder(message)[1](buf, out)
        if buf.pos != len(buf.data):
            raise WireError(f"{message}: {len(buf.data) - buf.pos} bytes left over")
        return out

    def default(self, f: sch.Field) -> Any:
        """The value a missing field `f` takes: its schema default, else zero, "", b"", []."""
        return _default(self.schema, f)

    def name_of(self, number: int) -> str | None:
        """The message name of a message type number (None if unknown)."""
        try:
            return self.msg(number).name
        except ValueError:
            return None

    # -- building --

    def _coder(self, name: str) -> tuple[Encoder, Decoder]:
        """Encoder and decoder of the record or message `name`."""
        coder = self._coders.get(name)
        if coder is None:
            coder = self._coders[name] = self._struct(self._structs[name])
        return coder

    def _struct(self, s: sch.Struct) -> tuple[Encoder, Decoder]:
        parts = [(f, *self._field(s, f)) for f in s.fields]

        def encode(out: list[bytes], obj: Any, where: str) -> None:
            for f, enc, _ in parts:
                if f.type.kind == "flags":
                    enc(out, obj, f"{where}.{f.name}")
                    continue
                value = _get(obj, f.name)
                enc(out, _default(self.schema, f) if value is _MISSING else value,
                    f"{where}.{f.name}")

        def decode(buf: _Buf, out: dict[str, Any]) -> None:
            for _, _, dec in parts:
                dec(buf, out)

        return encode, decode

    def _field(self, s: sch.Struct, f: sch.Field) -> tuple[Encoder, Decoder]:
        name = f.name
        if f.type.kind == "flags":
            flags = self.schema.enums[f.type.ref or ""]
            packer = _PACKERS[flags.base]
            default = set(f.default or [])
            mask = sum(b.value for b in flags.entries)

            def enc_flags(out: list[bytes], obj: Any, where: str) -> None:
                v = 0
                for b in flags.entries:
                    bit = _get(obj, b.name)
                    if bit is _MISSING:
                        bit = b.name in default
                    if bit:
                        v |= b.value
                out.append(packer.pack(v))

            def dec_flags(buf: _Buf, out: dict[str, Any]) -> None:
                v = buf.scalar(flags.base)
                if v & ~mask:
                    raise WireError(f"{s.name}.{name}: unknown bits 0x{v & ~mask:x}")
                for b in flags.entries:
                    out[b.name] = bool(v & b.value)

            return enc_flags, dec_flags
        enc, dec = self._value(f.type)

        def dec_field(buf: _Buf, out: dict[str, Any]) -> None:
            try:
                out[name] = dec(buf)
            except WireError as e:
                raise WireError(f"{s.name}.{name}: {e}") from None

        return enc, dec_field

    def _value(self, t: sch.Type) -> tuple[Encoder, ValueDecoder]:
        build = {"int": self._scalar, "f64": self._scalar, "bool": self._scalar,
                 "str": self._string, "bytes": self._string, "text": self._string,
                 "fixed": self._fixed, "tail": self._tail, "enum": self._enum,
                 "record": self._record, "list": self._list}.get(t.kind)
        if build is None:
            raise AssertionError(t.kind)
        return build(t)

    def _scalar(self, t: sch.Type) -> tuple[Encoder, ValueDecoder]:
        packer = _PACKERS[t.name]

        def enc_scalar(out: list[bytes], v: Any, where: str) -> None:
            try:
                out.append(packer.pack(v))
            except struct.error as e:
                raise WireError(f"{where}: {v!r} does not fit {t.name} ({e})") from None

        if t.kind == "bool":
            def dec_bool(buf: _Buf) -> bool:
                v = buf.scalar("bool")
                if v > 1:
                    raise WireError(f"bool of value {v}")
                return bool(v)
            return enc_scalar, dec_bool
        return enc_scalar, lambda buf: buf.scalar(t.name)

    def _string(self, t: sch.Type) -> tuple[Encoder, ValueDecoder]:
        width = self.schema.str_length if t.kind == "str" else "u32"
        counter = _PACKERS[width]
        limit = t.limit if t.limit is not None else (1 << (8 * counter.size)) - 1

        # encoding checks only a written limit: the frame's is the framing's to check
        enc_limit = limit if t.explicit else (1 << (8 * counter.size)) - 1

        def enc_str(out: list[bytes], v: Any, where: str) -> None:
            b = _to_bytes(v)
            if len(b) > enc_limit:
                raise WireError(f"{where}: {len(b)} bytes, more than {enc_limit}")
            out.append(counter.pack(len(b)))
            out.append(b)

        def dec_str(buf: _Buf) -> Any:
            n = buf.scalar(width)
            if n > limit:
                raise WireError(f"{n} bytes, more than {limit}")
            b = buf.take(n)
            return b if t.kind == "bytes" else b.decode(errors="replace")
        return enc_str, dec_str

    def _fixed(self, t: sch.Type) -> tuple[Encoder, ValueDecoder]:
        size = t.size or 0

        def enc_fixed(out: list[bytes], v: Any, where: str) -> None:
            b = _to_bytes(v)
            if len(b) != size:
                raise WireError(f"{where}: {len(b)} bytes, not {size}")
            out.append(b)
        return enc_fixed, lambda buf: buf.take(size)

    def _tail(self, t: sch.Type) -> tuple[Encoder, ValueDecoder]:
        def enc_tail(out: list[bytes], v: Any, where: str) -> None:
            out.append(_to_bytes(v))

        def dec_tail(buf: _Buf) -> bytes:
            return buf.take(len(buf.data) - buf.pos)
        return enc_tail, dec_tail

    def _enum(self, t: sch.Type) -> tuple[Encoder, ValueDecoder]:
        e = self.schema.enums[t.ref or ""]
        cls = self.enums[e.name]
        packer = _PACKERS[e.base]

        def enc_enum(out: list[bytes], v: Any, where: str) -> None:
            try:
                member = cls[v] if isinstance(v, str) else cls(v)
            except (KeyError, ValueError):
                raise WireError(f"{where}: {v!r} is no {e.name}") from None
            out.append(packer.pack(member))

        def dec_enum(buf: _Buf) -> enum.IntEnum:
            v = buf.scalar(e.base)
            try:
                return cls(v)
            except ValueError:
                raise WireError(f"{v} is no {e.name}") from None
        return enc_enum, dec_enum

    def _record(self, t: sch.Type) -> tuple[Encoder, ValueDecoder]:
        ref = t.ref or ""

        def enc_record(out: list[bytes], v: Any, where: str) -> None:
            self._coder(ref)[0](out, v, where)

        def dec_record(buf: _Buf) -> dict[str, Any]:
            rec: dict[str, Any] = {}
            self._coder(ref)[1](buf, rec)
            return rec
        return enc_record, dec_record

    def _list(self, t: sch.Type) -> tuple[Encoder, ValueDecoder]:
        assert t.item is not None
        item_enc, item_dec = self._value(t.item)
        min_item = self.schema.min_size(t.item)
        count = _PACKERS["u32"]

        def enc_list(out: list[bytes], v: Any, where: str) -> None:
            items = list(v)
            out.append(count.pack(len(items)))
            for i, item in enumerate(items):
                item_enc(out, item, f"{where}[{i}]")

        def dec_list(buf: _Buf) -> list[Any]:
            n = buf.scalar("u32")
            if min_item and n > (len(buf.data) - buf.pos) // min_item:
                raise WireError(f"short payload for a count of {n}")
            return [item_dec(buf) for _ in range(n)]
        return enc_list, dec_list


def _default(schema: sch.Schema, f: sch.Field) -> Any:
    if f.default is not None:
        return f.default
    kind = f.type.kind
    if kind in ("str", "text"):
        return ""
    if kind in ("bytes", "tail"):
        return b""
    if kind == "list":
        return []
    if kind == "record":
        return {}
    if kind == "fixed":
        return bytes(f.type.size or 0)
    if kind == "enum":
        return schema.enums[f.type.ref or ""].entries[0].value
    return 0


def load_codec(path: str) -> Codec:
    return Codec(sch.load(path))


DAEMON = Codec(sch.load(sch.DAEMON_SCHEMA))
