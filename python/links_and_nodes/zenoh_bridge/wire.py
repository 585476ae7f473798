"""What ln_zenoh puts on the Zenoh side (docs/zenoh.md): key expressions, the binary attachment
of every sample and service call, and the JSON form of service requests and responses.

Keys under a bridge's prefix P (default `ln/<instance>`):

    P/topic/<topic>          samples: the md's packed little-endian bytes, the attachment
    P/batch/<topic>          batches of samples for bridges (native core, ln_zenoh_core batch.rs)
    P/md/<md name>           queryable: the md's text with what it imports (ln-md-text)
    P/service/<name>         queryable: a call, request and response as JSON
    P/info/service/<name>    queryable: {"md_name", "layout_hash", "signature"} as JSON
    P/@live/bridge           liveliness token of the bridge
    P/@live/batch            liveliness token: its topics' samples also go in batches
    P/@live/topic/<topic>    liveliness token of each topic it publishes
    P/@live/service/<name>   liveliness token of each service it serves

Attachment (little-endian, 29 + N bytes; its layout and constants are read from
wire/zenoh.schema, the native core's attachment.rs shares its golden vectors):

    0   2  magic "LZ"         4  8  seq (u64)             20  8  layout hash (u64)
    2   1  version 1          12 8  publish time (i64 ns) 28  1  N, md name length
    3   1  flags, 0           29 N  md name (UTF-8)
"""

from __future__ import annotations

import fnmatch
import json
import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..wire import schema as _schema

SCHEMA = Path(_schema.__file__).with_name("zenoh.schema")
_SCHEMA = _schema.load(SCHEMA)
_FIELDS = _SCHEMA.messages["ATTACHMENT"].fields
_STRUCT_CODES = {"u8": "B", "u64": "Q", "i64": "q"}


def _head_format(fields: list[_schema.Field]) -> str:
    """The struct format of attachment fields: the md name stands for its length byte."""
    codes = [f"{f.type.size}s" if f.type.kind == "fixed"
             else _STRUCT_CODES[_SCHEMA.str_length if f.type.kind == "str" else f.type.name]
             for f in fields]
    return "<" + "".join(codes)


MAGIC = str(_SCHEMA.consts["MAGIC"].value).encode()
VERSION = int(_SCHEMA.consts["VERSION"].value)
MAX_MD_NAME = int(_SCHEMA.consts["MAX_MD_NAME"].value)
_HEAD = struct.Struct(_head_format(_FIELDS))  # "<2sBBQqQB"
HEAD_SIZE = _HEAD.size  # 29
# what changes with every sample: the fields before the layout hash
_SAMPLE_HEAD = struct.Struct(_head_format(_FIELDS[:[f.name for f in _FIELDS].index("layout_hash")]))
_BAD_KEY_CHARS = set("*$?#")


class AttachmentError(ValueError):
    """An attachment that is not one of ours: the sample is dropped and counted."""


@dataclass(frozen=True)
class Attachment:
    seq: int
    publish_time_ns: int
    layout_hash: int
    md_name: str

    def encode(self) -> bytes:
        name = self.md_name.encode()
        if not 0 < len(name) <= MAX_MD_NAME:
            raise ValueError(f"md name {self.md_name!r} must be 1..{MAX_MD_NAME} bytes")
        return _HEAD.pack(MAGIC, VERSION, 0, self.seq, self.publish_time_ns,
                          self.layout_hash, len(name)) + name


class AttachmentEncoder:
    """Attachments of one topic or service: the md part is packed once."""

    __slots__ = ("_tail",)
    _head = _SAMPLE_HEAD

    def __init__(self, md_name: str, layout_hash: int) -> None:
        self._tail = Attachment(0, 0, layout_hash, md_name).encode()[self._head.size:]

    def encode(self, seq: int, publish_time_ns: int) -> bytes:
        return self._head.pack(MAGIC, VERSION, 0, seq, publish_time_ns) + self._tail


def decode_attachment(data: bytes | None) -> Attachment:
    """The attachment of a sample or call; AttachmentError saying what is wrong."""
    if not data:
        raise AttachmentError("no attachment")
    if len(data) < HEAD_SIZE:
        raise AttachmentError(f"attachment of {len(data)} bytes, shorter than {HEAD_SIZE}")
    magic, version, _flags, seq, t_ns, layout_hash, n = _HEAD.unpack_from(data)
    if magic != MAGIC:
        raise AttachmentError(f"attachment magic {magic!r}, not {MAGIC!r}")
    if version != VERSION:
        raise AttachmentError(f"attachment version {version}, not {VERSION}")
    if len(data) != HEAD_SIZE + n or n == 0:
        raise AttachmentError(f"attachment of {len(data)} bytes for an md name of {n}")
    try:
        md_name = data[HEAD_SIZE:].decode()
    except UnicodeDecodeError:
        raise AttachmentError("md name in the attachment is not UTF-8") from None
    return Attachment(seq, t_ns, layout_hash, md_name)


# ---- key expressions ---------------------------------------------------------------------------

def bad_name(name: str) -> str | None:
    """Why `name` (a topic, service or md name) cannot be part of a key expression, or None."""
    if not name:
        return "it is empty"
    chunks = name.split("/")
    if any(not c for c in chunks):
        return "it has an empty '/'-separated part"
    if _BAD_KEY_CHARS & set(name):
        return "it holds one of * $ ? #"
    if any(c.startswith("@") for c in chunks):
        return "a '/'-separated part starts with @"
    return None


def topic_key(prefix: str, topic: str) -> str:
    return f"{prefix}/topic/{topic}"


def batch_key(prefix: str, topic: str) -> str:
    return f"{prefix}/batch/{topic}"


def md_key(prefix: str, md_name: str) -> str:
    return f"{prefix}/md/{md_name}"


def service_key(prefix: str, name: str) -> str:
    return f"{prefix}/service/{name}"


def service_info_key(prefix: str, name: str) -> str:
    return f"{prefix}/info/service/{name}"


def live_key(prefix: str, kind: str, name: str | None = None) -> str:
    """Liveliness token key: `P/@live/bridge`, `P/@live/topic/NAME`, `P/@live/service/NAME`."""
    return f"{prefix}/@live/{kind}" if name is None else f"{prefix}/@live/{kind}/{name}"


def name_in(key: str, prefix: str, kind: str) -> str | None:
    """The topic/service/md name of `key` under `P/<kind>/`, or None if it is not there."""
    head = f"{prefix}/{kind}/"
    return key[len(head):] if key.startswith(head) and len(key) > len(head) else None


def pattern_key(pattern: str) -> str:
    """A key expression that covers every name fnmatch `pattern` matches within one level of
    '/': `*` becomes `$*` inside a part, a part with `?` or `[` becomes `*`, a pattern of only
    `*` becomes `**`.  Names are still checked with fnmatch: this only narrows what Zenoh
    delivers."""
    if pattern.strip("*") == "":
        return "**"
    parts = []
    for part in pattern.split("/"):
        if "?" in part or "[" in part:
            parts.append("*")
            continue
        while "**" in part:
            part = part.replace("**", "*")
        parts.append("*" if part == "*" else part.replace("*", "$*"))
    return "/".join(parts)


def matches(name: str, pattern: str) -> bool:
    return fnmatch.fnmatchcase(name, pattern)


# ---- service fields as JSON --------------------------------------------------------------------

def encode_fields(message: Any) -> bytes:
    """A request or response struct as a JSON object of its fields (LnStruct.to_dict: numbers,
    strings, lists, nested objects; dynamic fields without their `_len`)."""
    return json.dumps(message.to_dict(), separators=(",", ":")).encode()


def decode_fields(data: bytes) -> dict[str, Any]:
    """The field dict of a JSON request or response; ValueError unless it is a JSON object."""
    value = json.loads(data.decode() if data else "{}")
    if not isinstance(value, dict):
        raise ValueError(f"expected a JSON object of fields, got {type(value).__name__}")
    return value
