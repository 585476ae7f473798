"""How a recording stores samples (docs/recording.md, "Encodings"): `ros2` (ros2msg schema,
CDR messages), `json` (jsonschema, JSON) or `ln` (the md's raw bytes, bit-exact).

    enc = channel_encoder("ros2", md_name, md_text, layout_hash, message_size)
    ch = enc.add_to(writer, "arm.state")           # McapWriter.add_channel with its schema
    writer.write(ch, seq, t_ns, enc.encode(raw))   # raw: the sample's ln bytes
    to_ln = ln_decoder(reader.topics()["arm.state"])
    raw = to_ln(sample.data)                       # any encoding back to the ln bytes

Every channel keeps md_name, layout_hash and message_size in its metadata whatever its
encoding, and channels not in `ln` keep the md text too (`md_text`), so each encoding
replays to the original layout without the md files of the recording system.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from ..mcap_format import MESSAGE_ENCODING, SCHEMA_ENCODING, TopicInfo, ln_metadata

ENCODINGS = ("ros2", "json", "ln")
DEFAULT_ENCODING = "ln"


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


def channel_encoder(encoding: str, md_name: str, md_text: bytes, layout_hash: int,
                    message_size: int, md_dirs: list[str] | None = None) -> ChannelEncoder:
    """The encoder of one topic's channel in `encoding` (one of ENCODINGS)."""
    if encoding == "ln":
        return ChannelEncoder("ln", md_name, SCHEMA_ENCODING, bytes(md_text), MESSAGE_ENCODING,
                              ln_metadata(md_name, layout_hash, message_size), _identity)
    raise EncodingError(f"unknown encoding {encoding!r}: one of {', '.join(ENCODINGS)}")


def ln_decoder(info: TopicInfo, md_dirs: list[str] | None = None) -> Callable[[bytes], bytes]:
    """The function from a channel's stored message bytes to the md's ln bytes."""
    if info.message_encoding == MESSAGE_ENCODING:
        return _identity
    raise EncodingError(f"topic '{info.topic}': message encoding "
                        f"'{info.message_encoding}' is not one ln reads")
