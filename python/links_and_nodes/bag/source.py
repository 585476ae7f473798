"""One input recording read in one pass: as (TopicInfo, Sample) pairs, or as blocks (chunks
still compressed, which a command may copy whole, and messages outside chunks).  A corrupt
or cut-short file ends the stream at the bad record and keeps the McapError, so a command
finishes its output with what came before."""

from __future__ import annotations

import os
from collections.abc import Iterator

from ..mcap_format import McapError, McapReader, Message, RawChunk, Sample, TopicInfo

# files of McapWriter: log time == publish time, so a chunk's times are publish times
LN_LIBRARY = "links_and_nodes"


class Source:
    """An input file; iterate it once, then look at `error`/`complete`."""

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = str(path)
        self.reader = McapReader(self.path)
        self.error: McapError | None = None

    @property
    def complete(self) -> bool:
        """The whole file was read, up to its footer."""
        return self.reader.complete and self.error is None

    @property
    def ln_written(self) -> bool:
        """Written by McapWriter: every message's log time is its publish time."""
        return self.reader.writer_library.startswith(LN_LIBRARY)

    def __iter__(self) -> Iterator[tuple[TopicInfo, Sample]]:
        self.error = None
        try:
            yield from self.reader.items()
        except McapError as exc:
            self.error = exc

    def blocks(self) -> Iterator[RawChunk | Message]:
        """reader.blocks(); a bad record ends it (kept in `error`)."""
        self.error = None
        try:
            yield from self.reader.blocks()
        except McapError as exc:
            self.error = exc

    def chunk_infos(self, chunk: RawChunk) -> list[TopicInfo] | None:
        """The channels of `chunk` by its Message Indexes; None when they may not tell all
        (no or cut-short indexes) or name a channel that is not a known ln channel."""
        if not chunk.indexed or not chunk.indexes:
            return None
        infos = [self.reader.channel(c) for c in chunk.indexes]
        return None if any(i is None for i in infos) else infos  # type: ignore[return-value]


def first_error(sources: list[Source]) -> McapError | None:
    return next((s.error for s in sources if s.error is not None), None)
