"""What a recording says about itself without reading its samples: the summary section
(Statistics, Chunk Indexes) when the file has one, else a walk over the top-level record
headers that seeks past every chunk's data.  Reads a few bytes per chunk either way; a
malformed file simply yields less here (the streaming pass reports what is wrong)."""

from __future__ import annotations

import os
import struct
from collections import Counter
from dataclasses import dataclass, field
from typing import BinaryIO

from ..mcap_format import CHUNK, CHUNK_INDEX, FOOTER, MAGIC, MESSAGE, STATISTICS

_REC = struct.Struct("<BQ")
_FOOTER = struct.Struct("<QQI")
_STATS = struct.Struct("<QHIIIIQQ")  # counts of messages..chunks, start, end
_CHUNK_TIMES = struct.Struct("<QQ")
_MSG_TIME = struct.Struct("<HIQQ")


@dataclass
class Layout:
    """Counts and times of a file, from its summary (`summary` True) or its chunk headers."""

    summary: bool = False
    message_count: int | None = None  # from Statistics
    channel_counts: dict[int, int] = field(default_factory=dict)  # channel id -> messages
    chunk_count: int = 0
    compressions: Counter[str] = field(default_factory=Counter)  # "none", "zstd", "lz4"
    first_ns: int | None = None
    last_ns: int | None = None
    compressed_bytes: int = 0
    uncompressed_bytes: int = 0

    def add_times(self, t0: int, t1: int) -> None:
        self.first_ns = t0 if self.first_ns is None else min(self.first_ns, t0)
        self.last_ns = t1 if self.last_ns is None else max(self.last_ns, t1)


def _string(body: bytes, at: int) -> tuple[str, int]:
    (n,) = struct.unpack_from("<I", body, at)
    return body[at + 4:at + 4 + n].decode(errors="replace"), at + 4 + n


def _summary_start(f: BinaryIO, size: int) -> int | None:
    tail = _REC.size + _FOOTER.size + len(MAGIC)
    if size < len(MAGIC) + tail:
        return None
    f.seek(size - tail)
    data = f.read(tail)
    opcode, length = _REC.unpack_from(data)
    if data[-len(MAGIC):] != MAGIC or opcode != FOOTER or length != _FOOTER.size:
        return None
    start = _FOOTER.unpack_from(data, _REC.size)[0]
    return start if len(MAGIC) <= start <= size - tail else None


def _statistics(layout: Layout, body: bytes) -> None:
    stats = _STATS.unpack_from(body)
    layout.message_count, layout.chunk_count = stats[0], stats[5]
    if stats[0]:
        layout.add_times(stats[6], stats[7])
    (n,) = struct.unpack_from("<I", body, _STATS.size)
    at = _STATS.size + 4
    for _ in range(n // 10):
        channel, count = struct.unpack_from("<HQ", body, at)
        layout.channel_counts[channel] = count
        at += 10


def _chunk_index(layout: Layout, body: bytes) -> None:
    (n,) = struct.unpack_from("<I", body, 32)
    at = 36 + n + 8
    compression, at = _string(body, at)
    csize, usize = struct.unpack_from("<QQ", body, at)
    layout.compressions[compression or "none"] += 1
    layout.compressed_bytes += csize
    layout.uncompressed_bytes += usize


def _read_summary(f: BinaryIO, start: int, end: int) -> Layout:
    layout = Layout(summary=True)
    chunks = 0
    at = start
    while at + _REC.size <= end:
        f.seek(at)
        opcode, length = _REC.unpack(f.read(_REC.size))
        if opcode in (STATISTICS, CHUNK_INDEX):  # one record at a time, never the section
            body = f.read(length)
            if opcode == STATISTICS:
                _statistics(layout, body)
            else:
                _chunk_index(layout, body)
                chunks += 1
        at += _REC.size + length
    layout.chunk_count = max(layout.chunk_count, chunks)
    return layout


def _walk(f: BinaryIO, size: int) -> Layout:
    """Top-level records from the start: chunk headers (times, compression), seeking past
    their data; loose messages' times."""
    layout = Layout()
    at = len(MAGIC)
    while at + _REC.size <= size:
        f.seek(at)
        opcode, length = _REC.unpack(f.read(_REC.size))
        if at + _REC.size + length > size or opcode == FOOTER:
            break
        if opcode == CHUNK:
            head = f.read(min(length, 4096))
            t0, t1 = _CHUNK_TIMES.unpack_from(head)
            compression, after = _string(head, 28)
            (csize,) = struct.unpack_from("<Q", head, after)
            layout.add_times(t0, t1)
            layout.chunk_count += 1
            layout.compressions[compression or "none"] += 1
            layout.compressed_bytes += csize
            layout.uncompressed_bytes += struct.unpack_from("<Q", head, 16)[0]
        elif opcode == MESSAGE:
            t = _MSG_TIME.unpack(f.read(_MSG_TIME.size))[3]
            layout.add_times(t, t)
        at += _REC.size + length
    return layout


def read_layout(path: str | os.PathLike[str]) -> Layout:
    """The Layout of `path`: an empty one if it cannot be read."""
    try:
        with open(path, "rb") as f:
            size = os.fstat(f.fileno()).st_size
            start = _summary_start(f, size)
            try:
                if start is not None:
                    return _read_summary(f, start, size - _REC.size - _FOOTER.size
                                         - len(MAGIC))
                return _walk(f, size)
            except (struct.error, ValueError):
                return Layout()
    except OSError:
        return Layout()


def first_time(paths: list[str]) -> int | None:
    """The earliest sample time of the files, from their summaries or chunk headers."""
    times = [t for t in (read_layout(p).first_ns for p in paths) if t is not None]
    return min(times) if times else None
