"""`ln_bag convert --encoding ros2|json|ln`: every channel re-encoded (record.encodings:
ln_decoder to the md's ln bytes, then channel_encoder's encode); samples keep their topic,
sequence number and publish time, channels their metadata.  A channel already in the
encoding is copied unchanged (its chunks as stored)."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from ..mcap_format import TopicInfo
from ..record.encodings import ENCODINGS, EncodingError, channel_encoder, ln_decoder
from .copying import Rules, copy
from .errors import BagError

HELP = "re-encode every channel: ros2 (CDR), json or ln (raw md bytes)"


def add_arguments(ap: argparse.ArgumentParser) -> None:
    ap.add_argument("--encoding", required=True, choices=ENCODINGS,
                    help="of the output's channels")
    ap.add_argument("--md-dir", action="append", default=[], metavar="DIR",
                    help="search DIR for an md a channel does not carry (may be repeated)")


def planner(encoding: str, md_dirs: list[str] | None
            ) -> Callable[[TopicInfo], tuple[dict[str, Any] | None, Callable[[Any], Any] | None]]:
    def plan(info: TopicInfo) -> tuple[dict[str, Any] | None, Callable[[Any], Any] | None]:
        try:
            decode = ln_decoder(info, md_dirs)
            enc = channel_encoder(encoding, info.md_name, info.md_text, info.layout_hash,
                                  info.message_size, md_dirs)
        except Exception as exc:  # noqa: BLE001 - EncodingError, MdError: say which md
            kind = "" if isinstance(exc, EncodingError) else f"{type(exc).__name__}: "
            raise BagError(f"topic '{info.topic}': md '{info.md_name}' cannot be converted "
                           f"to {encoding}: {kind}{exc}") from None
        if (enc.message_encoding, enc.schema_encoding) == (info.message_encoding,
                                                            info.schema_encoding):
            return None, None  # already in the encoding: copied unchanged
        metadata = {k: v for k, v in info.metadata.items() if k != "md_text"}
        metadata.update(enc.metadata)
        spec = {"schema_name": enc.schema_name, "schema_encoding": enc.schema_encoding,
                "schema_data": enc.schema_data, "message_encoding": enc.message_encoding,
                "metadata": metadata}
        encode = enc.encode

        def transform(data: Any) -> Any:
            try:
                return encode(decode(bytes(data)))
            except EncodingError as exc:
                raise BagError(f"topic '{info.topic}': a sample of md '{info.md_name}' "
                               f"cannot be converted to {encoding}: {exc}") from None

        return spec, transform

    return plan


def run(args: argparse.Namespace) -> int:
    return copy(args, Rules(plan=planner(args.encoding, args.md_dir or None)))
