"""Where ln_bag writes: output checks (never an input, never an existing file without
--force), the names of split pieces, and the writer that copies channels unchanged (with
their ids) and whole chunks of an input that use its compression."""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Any

from ..mcap_format import COMPRESSIONS, DEFAULT_CHUNK_SIZE, McapWriter, RawChunk, TopicInfo
from .errors import BagError
from .summary import read_layout

WRITER_NAME = "links_and_nodes ln_bag"


def add_output_args(ap: argparse.ArgumentParser, what: str = "FILE") -> None:
    ap.add_argument("-o", "--output", required=True, metavar=what, help="the output")
    ap.add_argument("-f", "--force", action="store_true", help="replace an existing output")


def add_writer_args(ap: argparse.ArgumentParser) -> None:
    ap.add_argument("--compression", choices=COMPRESSIONS, default=None,
                    help="of each output chunk (default: as the first input's chunks, zstd "
                    "if it has none); chunks in this compression are copied without "
                    "decompressing where all their samples are kept")
    ap.add_argument("--chunk-size", type=parse_size, default=DEFAULT_CHUNK_SIZE,
                    metavar="SIZE", help="samples per output chunk, in bytes (default 1MiB)")


def input_compression(paths: list[str]) -> str:
    """The compression most chunks of the first input use ("zstd" if it has none)."""
    found = read_layout(paths[0]).compressions.most_common(1) if paths else []
    return found[0][0] if found and found[0][0] in COMPRESSIONS else "zstd"


def parse_size(text: str) -> int:
    """ln_record's sizes ("1GiB", "500MB", "4096"); imported here when used: ln_record's
    module takes long to import, and ln_bag starts for every command."""
    from ..record.record_cli import parse_size as parse

    return parse(text)


def check_output(path: str | os.PathLike[str], inputs: list[str], force: bool) -> None:
    """BagError if `path` is one of `inputs` (the same file by any name) or exists and not
    `force`."""
    out = Path(path)
    for name in inputs:
        try:
            if out.exists() and os.path.samefile(out, name):
                raise BagError(f"{out}: is the input {name}: refusing to write over an input")
        except OSError:
            continue
    if out.exists() and not force:
        raise BagError(f"{out}: exists: give --force to replace it")


def piece_name(base: str | os.PathLike[str], index: int) -> Path:
    """The name of split piece `index`: BASE_NNNN.mcap (a `.mcap` ending of BASE dropped)."""
    text = str(base)
    if text.endswith(".mcap"):
        text = text[:-len(".mcap")]
    return Path(f"{text}_{index:04d}.mcap")


class Output:
    """An McapWriter whose channels are registered on first use, copied from the input's
    TopicInfo unchanged (or as `encoder` makes them); one channel per topic name."""

    def __init__(self, path: str | os.PathLike[str], args: argparse.Namespace) -> None:
        self.path = Path(path)
        compression = args.compression or input_compression(args.inputs)
        try:
            self.writer = McapWriter(path, compression, args.chunk_size,
                                     writer_name=WRITER_NAME, overwrite=True)
        except (OSError, ValueError, ImportError) as exc:
            raise BagError(f"{path}: cannot write: {exc}") from None
        # the MCAP name of the chunks' compression: that of the chunks copy_chunk() takes
        self.chunk_compression = "" if compression == "none" else compression
        self.channels: dict[str, tuple[TopicInfo, int]] = {}
        self.samples = 0
        self.copied_chunks = 0  # chunks copied as stored (the fast path), for tests/stats

    def channel(self, info: TopicInfo, spec: dict[str, Any] | None = None) -> int:
        """The output channel of `info`'s topic; BagError if the topic came with another md,
        layout or encoding before.  `spec`: add_channel's keywords (default: `info`'s)."""
        known = self.channels.get(info.topic)
        if known is not None:
            old = known[0]
            if (old.md_name, old.layout_hash, old.message_encoding) != (
                    info.md_name, info.layout_hash, info.message_encoding):
                raise BagError(
                    f"topic '{info.topic}' has md '{old.md_name}' (layout hash "
                    f"{old.layout_hash:016x}, encoding {old.message_encoding}) in one input "
                    f"and '{info.md_name}' ({info.layout_hash:016x}, "
                    f"{info.message_encoding}) in another")
            return known[1]
        # the input's id where it is free, so that chunks of the input can be copied
        same = None if info.channel_id in self.writer.channel_ids else info.channel_id
        channel = self.writer.add_channel(info.topic, **(spec or copy_spec(info)),
                                          channel_id=same)
        self.channels[info.topic] = (info, channel)
        return channel

    def write(self, channel: int, seq: int, t_ns: int, data: Any) -> None:
        self.writer.write(channel, seq, t_ns, data)
        self.samples += 1

    def can_copy(self, chunk: RawChunk, infos: list[TopicInfo]) -> bool:
        """`chunk` (of channels `infos`, copied unchanged) can go to the file as stored: it
        has the output's compression, and its channels have their ids here (registering
        them if new)."""
        if chunk.compression != self.chunk_compression:
            return False
        return all(self.channel(info) == info.channel_id for info in infos)

    def copy_chunk(self, chunk: RawChunk) -> None:
        self.writer.copy_chunk(chunk)
        self.samples += chunk.message_count
        self.copied_chunks += 1

    def close(self) -> None:
        try:
            self.writer.close()
        except OSError as exc:
            raise BagError(f"{self.path}: cannot write: {exc}") from None


def copy_spec(info: TopicInfo) -> dict[str, Any]:
    """McapWriter.add_channel's keywords that copy `info`'s channel unchanged."""
    return {"schema_name": info.schema_name, "schema_encoding": info.schema_encoding,
            "schema_data": info.schema_data, "message_encoding": info.message_encoding,
            "metadata": info.metadata}
