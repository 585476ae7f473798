"""Rotating MCAP output of ln_record: DIR/PREFIX_0000.mcap, PREFIX_0001.mcap, ...

Each file is complete on its own: it repeats the schema and channel of every topic, with the
same channel ids in every file.  A new file starts once the current one (written bytes plus
the open chunk) reaches the split size.  Not thread-safe: the recorder serializes.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..mcap_format import McapWriter
from .background_writer import BackgroundMcapWriter
from .encodings import ChannelEncoder


class SplitWriter:
    """McapWriters one after the other; split_size 0: one file."""

    def __init__(self, directory: Path, prefix: str, compression: str, chunk_size: int,
                 split_size: int, writer_name: str = "links_and_nodes ln_record") -> None:
        self.directory = directory
        self.prefix = prefix
        self.compression = compression
        self.chunk_size = chunk_size
        self.split_size = split_size
        self.writer_name = writer_name
        self.files: list[Path] = []
        self._channels: list[tuple[str, ChannelEncoder]] = []
        self.bytes_closed = 0  # of the files finished before the current one
        self._writer = self._open()

    @property
    def writer(self) -> McapWriter:
        return self._writer

    @property
    def size(self) -> int:
        """Bytes written into all files so far (the open chunk not included)."""
        return self.bytes_closed + self._writer.offset

    def _open(self) -> McapWriter:
        path = self.directory / f"{self.prefix}_{len(self.files):04d}.mcap"
        writer = BackgroundMcapWriter(path, self.compression, self.chunk_size,
                                      writer_name=self.writer_name, overwrite=False)
        self.files.append(path)
        for topic, encoder in self._channels:
            encoder.add_to(writer, topic)
        return writer

    def add_channel(self, topic: str, encoder: ChannelEncoder) -> int:
        """The channel id of a new topic stored as `encoder` says (the same in every file)."""
        self._channels.append((topic, encoder))
        return encoder.add_to(self._writer, topic)

    def add_topic(self, topic: str, md_name: str, md_text: bytes, layout_hash: int,
                  message_size: int) -> int:
        """The channel id of a new topic stored as raw ln bytes (encoding `ln`)."""
        from .encodings import channel_encoder

        return self.add_channel(topic, channel_encoder("ln", md_name, md_text, layout_hash,
                                                       message_size))

    def write(self, channel: int, seq: int, publish_time_ns: int, data: Any) -> None:
        w = self._writer
        w.write(channel, seq, publish_time_ns, data)
        if self.split_size and w.offset + w.pending >= self.split_size:
            self.rotate()

    def flush(self) -> None:
        self._writer.flush()

    def rotate(self) -> None:
        """Finish the current file and go on in the next one."""
        self._writer.close()
        self.bytes_closed += self._writer.offset
        self._writer = self._open()

    def close(self) -> None:
        self._writer.close()
