"""How a recording stores samples (docs/recording.md, "Encodings"): `ros2` (ros2msg schema,
CDR messages), `json` (jsonschema, JSON) or `ln` (the md's raw bytes, bit-exact).

    enc = channel_encoder("ros2", md_name, md_text, layout_hash, message_size)
    ch = enc.add_to(writer, "arm.state")           # McapWriter.add_channel with its schema
    writer.write(ch, seq, t_ns, enc.encode(raw))   # raw: the sample's ln bytes
    to_ln = ln_decoder(reader.topics()["arm.state"])
    raw = to_ln(sample.data)                       # any encoding back to the ln bytes

Every channel keeps md_name, layout_hash and message_size in its metadata whatever its
encoding, and channels not in `ln` keep the md text too (`md_text`), so each encoding
replays to the original layout without the md files of the recording system: the md is
always built from that text (written into a temporary md directory), on both sides.
`ros2` and `ln` keep every bit; `json` keeps every number (float32 and float64 exactly) but
not NaN payload bits, nor a char field's bytes after its first NUL or that are not UTF-8.
"""

from __future__ import annotations

import hashlib
import json
import tempfile
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from .. import md_json
from ..mcap_format import (
    MESSAGE_ENCODING,
    SCHEMA_ENCODING,
    TopicInfo,
    ln_metadata,
    md_schema_text,
    write_md_files,
)
from .defaults import ENCODINGS

ROS2_SCHEMA, ROS2_MESSAGE = "ros2msg", "cdr"
JSON_SCHEMA, JSON_MESSAGE = md_json.SCHEMA_ENCODING, "json"


class EncodingError(ValueError):
    """A sample or md that an encoding cannot take; the text names what and why."""


@dataclass
class ChannelEncoder:
    """One channel's schema and the function from ln bytes to its message bytes."""

    encoding: str
    schema_name: str
    schema_encoding: str
    schema_data: bytes
    message_encoding: str
    metadata: dict[str, str]
    encode: Callable[[Any], Any] = field(repr=False)

    def add_to(self, writer: Any, topic: str) -> int:
        """Register the channel with an McapWriter: its id."""
        return int(writer.add_channel(
            topic, schema_name=self.schema_name, schema_encoding=self.schema_encoding,
            schema_data=self.schema_data, message_encoding=self.message_encoding,
            metadata=self.metadata))


def _identity(data: Any) -> Any:
    return data


# ---- the md of a channel, from its text --------------------------------------------------------
_codecs: dict[tuple[str, str, bytes], Any] = {}  # (kind, md name, md text) -> md or codec
_lock = threading.Lock()


def _from_text(kind: str, md_name: str, md_text: bytes, md_dirs: list[str] | None) -> Any:
    """The MessageDef (kind "md") or ros2 CdrCodec (kind "ros2") of `md_name`, built from
    `md_text` (an ln-md-text schema) alone, or found in `md_dirs` when there is no text.
    Cached per text: ln_play and converters ask once per channel, tests once per sample."""
    key = (kind, md_name, bytes(md_text))
    with _lock:
        found = _codecs.get(key)
    if found is not None:
        return found
    from .. import ros2
    from ..ros2.types import load_md

    make = ros2.codec if kind == "ros2" else load_md
    if md_text:
        # the directory's name carries the text's hash: the ros2 codec cache is keyed on it
        digest = hashlib.sha256(md_text).hexdigest()[:16]
        with tempfile.TemporaryDirectory(prefix=f"ln_md.{digest}.") as tmp:
            write_md_files(md_text, tmp)
            found = make(md_name, [tmp])
    else:
        found = make(md_name, md_dirs)
    with _lock:
        return _codecs.setdefault(key, found)


def _check_layout(md_name: str, md: Any, layout_hash: int, message_size: int) -> None:
    if md.layout_hash != layout_hash or md.struct.size != message_size:
        raise EncodingError(f"md '{md_name}' from the recorded md text has layout hash "
                            f"0x{md.layout_hash:016x} and {md.struct.size} bytes, the channel "
                            f"says 0x{layout_hash:016x} and {message_size} bytes")


def _md_text_entry(md_name: str, md_text: bytes) -> str:
    try:
        return bytes(md_text).decode()
    except UnicodeDecodeError as exc:
        raise EncodingError(f"md '{md_name}': its text is not UTF-8 (byte {exc.start}): use "
                            "--encoding ln") from None


# ---- encoders ---------------------------------------------------------------------------------
def channel_encoder(encoding: str, md_name: str, md_text: bytes, layout_hash: int,
                    message_size: int, md_dirs: list[str] | None = None) -> ChannelEncoder:
    """The encoder of one topic's channel in `encoding` (one of ENCODINGS).  md_text: the
    ln-md-text schema of the md (md_schema_text(md_name, md_dirs) when empty).  Raises
    EncodingError for an md the encoding refuses (the text says why)."""
    if encoding not in ENCODINGS:
        raise EncodingError(f"unknown encoding {encoding!r}: one of {', '.join(ENCODINGS)}")
    if not md_text:
        md_text = md_schema_text(md_name, md_dirs)
    md_text = bytes(md_text)
    if encoding == "ln":
        return ChannelEncoder("ln", md_name, SCHEMA_ENCODING, md_text, MESSAGE_ENCODING,
                              ln_metadata(md_name, layout_hash, message_size), _identity)
    meta = ln_metadata(md_name, layout_hash, message_size,
                       md_text=_md_text_entry(md_name, md_text))
    if encoding == "ros2":
        return _ros2_encoder(md_name, md_text, layout_hash, message_size, meta)
    return _json_encoder(md_name, md_text, layout_hash, message_size, meta)


def _ros2_encoder(md_name: str, md_text: bytes, layout_hash: int, message_size: int,
                  meta: dict[str, str]) -> ChannelEncoder:
    from ..ros2 import CdrError

    try:
        codec = _from_text("ros2", md_name, md_text, None)
        md = _from_text("md", md_name, md_text, None)
    except CdrError as exc:
        raise EncodingError(str(exc)) from None
    _check_layout(md_name, md, layout_hash, message_size)
    meta["ros2_type_hash"] = codec.type_hash
    return ChannelEncoder("ros2", codec.type_name, ROS2_SCHEMA, codec.schema_text.encode(),
                          ROS2_MESSAGE, meta, codec.encode)


def _json_encoder(md_name: str, md_text: bytes, layout_hash: int, message_size: int,
                  meta: dict[str, str]) -> ChannelEncoder:
    from ..tools.introspection import values as fmt

    md = _from_text("md", md_name, md_text, None)
    if md.kind != "message":
        raise EncodingError(f"md '{md_name}' is a {md.kind}, not a message")
    layout = md.struct
    if layout.has_dynamic:
        raise EncodingError(f"md '{md_name}' has dynamic fields: a sample holds their "
                            "pointers, not their data")
    _check_layout(md_name, md, layout_hash, message_size)
    schema = json.dumps(md_json.root_schema(layout, md.doc)).encode()
    encode_json, decode = md_json.encode, fmt.decode

    def encode(raw: Any) -> bytes:
        return encode_json(decode(layout, raw))

    return ChannelEncoder("json", md_name, JSON_SCHEMA, schema, JSON_MESSAGE, meta, encode)


# ---- decoders ---------------------------------------------------------------------------------
def ln_decoder(info: TopicInfo, md_dirs: list[str] | None = None) -> Callable[[bytes], bytes]:
    """The function from a channel's stored message bytes to the md's ln bytes.  The md comes
    from the channel's `md_text` metadata (else from `md_dirs`).  The function raises
    EncodingError for bytes that are not a sample of the md."""
    if info.message_encoding == MESSAGE_ENCODING:
        return _identity
    if info.message_encoding == ROS2_MESSAGE:
        return _ros2_decoder(info, md_dirs)
    if info.message_encoding == JSON_MESSAGE:
        return _json_decoder(info, md_dirs)
    raise EncodingError(f"topic '{info.topic}': message encoding "
                        f"'{info.message_encoding}' is not one ln reads")


def _ros2_decoder(info: TopicInfo, md_dirs: list[str] | None) -> Callable[[bytes], bytes]:
    from ..ros2 import CdrError

    try:
        codec = _from_text("ros2", info.md_name, info.md_text, md_dirs)
        md = _from_text("md", info.md_name, info.md_text, md_dirs)
    except CdrError as exc:
        raise EncodingError(f"topic '{info.topic}': {exc}") from None
    _check_layout(info.md_name, md, info.layout_hash, info.message_size)
    decode, topic = codec.decode, info.topic

    def to_ln(data: bytes) -> bytes:
        try:
            return decode(data)
        except CdrError as exc:
            raise EncodingError(f"topic '{topic}': {exc}") from None

    return to_ln


def _json_decoder(info: TopicInfo, md_dirs: list[str] | None) -> Callable[[bytes], bytes]:
    md = _from_text("md", info.md_name, info.md_text, md_dirs)
    _check_layout(info.md_name, md, info.layout_hash, info.message_size)
    layout, topic, to_bytes = md.struct, info.topic, md_json.to_bytes

    def to_ln(data: bytes) -> bytes:
        try:
            return to_bytes(layout, json.loads(data))
        except ValueError as exc:  # JSONDecodeError (with its position) and JsonValueError
            raise EncodingError(f"topic '{topic}': a JSON sample of md '{layout.md_name}': "
                                f"{exc}") from None

    return to_ln
