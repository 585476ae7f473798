"""A Chunk record of an MCAP file kept as stored (compressed): what McapReader.blocks()
yields and McapWriter.copy_chunk() copies without decompressing, and the parsing of the
Message Index records that follow a chunk."""

from __future__ import annotations

import os
import struct
from dataclasses import dataclass, field
from typing import Any

COMPRESSIONS = ("zstd", "lz4", "none")  # of chunks; mcap_format.py compresses them
DEFAULT_CHUNK_SIZE = 1 << 20  # bytes of records in a chunk before it is written
_REC_SIZE = 9  # a record's opcode and length
_IDX_SIZE = 16  # a Message Index entry: log time, offset in the chunk


@dataclass(frozen=True, eq=False)
class RawChunk:
    """A Chunk record of a file's data section as stored, not decompressed: its parsed
    header and the Message Index records that follow it (McapReader.blocks()).
    McapWriter.copy_chunk() copies it; McapReader.chunk_messages() decodes it.  Where the
    pass did not need its bytes (no data CRC to compute) they stay in the file: `body` and
    copy_body() read them from the reader's open file, so only while the pass is open."""

    offset: int  # of the record in its file
    head: bytes  # the record's opcode and length
    body_size: int  # bytes of the rest of the record: header fields, compressed records
    start_ns: int  # message_start_time (the earliest log time in it)
    end_ns: int  # message_end_time
    uncompressed_size: int
    uncompressed_crc: int
    compression: str  # as MCAP names it: "" (none), "zstd", "lz4"
    data_at: int  # where the compressed records start in `body`
    indexes: dict[int, bytes]  # channel id -> its Message Index entries (log time, offset)
    indexed: bool  # a record after the Message Indexes shows they are all there
    stored: bytes | None = field(default=None, repr=False)  # the body, where it was read
    file: Any = field(default=None, repr=False, compare=False)  # else: the open input

    @property
    def body(self) -> bytes:
        """The rest of the record as in the file."""
        if self.stored is not None:
            return self.stored
        data = os.pread(self.file.fileno(), self.body_size, self.offset + _REC_SIZE)
        if len(data) != self.body_size:
            raise OSError(f"the chunk at byte {self.offset} is no longer in the file")
        return data

    def copy_body(self, fd: int) -> None:
        """Write the body to `fd` (in the kernel, without reading it here, where it can)."""
        if self.stored is not None or not hasattr(os, "copy_file_range"):
            write_all(fd, self.body)
            return
        src, at, left = self.file.fileno(), self.offset + _REC_SIZE, self.body_size
        try:
            while left:
                n = os.copy_file_range(src, fd, left, at)
                if n <= 0:
                    raise OSError("copy_file_range copied nothing")
                at += n
                left -= n
        except OSError:  # a file system that does not do it: the rest through memory
            write_all(fd, os.pread(src, left, at))

    @property
    def compressed_size(self) -> int:
        return self.body_size - self.data_at

    @property
    def message_count(self) -> int:
        return sum(len(e) for e in self.indexes.values()) // _IDX_SIZE


def write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]


def index_record(body: bytes) -> tuple[int, bytes] | None:
    """(channel, entries) of a Message Index record; None for a malformed one."""
    if len(body) < 6:
        return None
    channel, n = struct.unpack_from("<HI", body)
    if n != len(body) - 6 or n % _IDX_SIZE:
        return None
    return channel, body[6:]
