"""Recordings of topics as MCAP files: the mapping (docs/recording.md), a writer and a reader.

    with McapWriter("run_0000.mcap", compression="zstd") as out:
        ch = out.add_topic("arm.state", "robot/joint_state", md_schema_text("robot/joint_state"),
                           layout_hash, message_size)
        out.write(ch, seq, publish_time_ns, raw_bytes)
    for topic, md_name, layout_hash, seq, t_ns, data in iter_mcap("run_0000.mcap"):
        ...
    read_topics("run_0000.mcap")["arm.state"].md_text   # the md, with what it imports

One channel per topic (message encoding "ln-md": the raw bytes of the md's packed
little-endian layout), one schema per md (encoding "ln-md-text": the definition text and
every md it imports, so a file decodes without the md files).  Written against the MCAP
spec with Python's own modules only; zstandard and lz4 are needed only for chunks
compressed with them.  Chunks go to the file whole, in one write each, so a recorder killed
at any moment leaves a file that readers (this one, and MCAP stream readers) read up to its
last complete chunk; only the summary and footer are missing.  McapReader.blocks() gives
the chunks still compressed (RawChunk), which McapWriter.copy_chunk() copies as stored.
"""

from __future__ import annotations

import os
import re
import struct
import tempfile
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, NamedTuple

from .mcap_chunk import COMPRESSIONS, DEFAULT_CHUNK_SIZE, RawChunk, index_record

MAGIC = b"\x89MCAP0\r\n"
SCHEMA_ENCODING = "ln-md-text"
MESSAGE_ENCODING = "ln-md"
SCHEMA_MARK = b"--- "  # starts the line before each md of a schema's text

# opcodes of the MCAP records used here
HEADER, FOOTER, SCHEMA, CHANNEL, MESSAGE, CHUNK, MESSAGE_INDEX, CHUNK_INDEX = range(1, 9)
STATISTICS, SUMMARY_OFFSET, DATA_END = 0x0B, 0x0E, 0x0F
_NAMES = {HEADER: "Header", FOOTER: "Footer", SCHEMA: "Schema", CHANNEL: "Channel",
          MESSAGE: "Message", CHUNK: "Chunk", MESSAGE_INDEX: "MessageIndex",
          CHUNK_INDEX: "ChunkIndex", STATISTICS: "Statistics",
          SUMMARY_OFFSET: "SummaryOffset", DATA_END: "DataEnd"}

_REC = struct.Struct("<BQ")  # opcode, record length
_MSG = struct.Struct("<BQHIQQ")  # record head + channel, sequence, log_time, publish_time
_MSG_BODY = struct.Struct("<HIQQ")
_IDX = struct.Struct("<QQ")  # message index entry: log_time, offset in the chunk
_CHUNK_HEAD = struct.Struct("<QQQI")  # start, end, uncompressed size, uncompressed crc
_U16, _U32, _U64 = struct.Struct("<H"), struct.Struct("<I"), struct.Struct("<Q")


def ln_metadata(md_name: str, layout_hash: int, message_size: int, **extra: str
                ) -> dict[str, str]:
    """The channel metadata every ln channel carries, whatever its encoding."""
    return {"md_name": md_name, "layout_hash": f"{layout_hash:016x}",
            "message_size": str(message_size), **extra}


def _s(text: str) -> bytes:
    data = text.encode()
    return _U32.pack(len(data)) + data


def _record(opcode: int, body: bytes) -> bytes:
    return _REC.pack(opcode, len(body)) + body


def _str_map(entries: dict[str, str]) -> bytes:
    data = b"".join(_s(k) + _s(v) for k, v in entries.items())
    return _U32.pack(len(data)) + data


def _compressor(compression: str) -> tuple[str, Callable[[bytes], bytes] | None]:
    """(MCAP compression name, function) of `compression`; ValueError for an unknown one,
    ImportError naming the package for one whose module is missing."""
    if compression == "none":
        return "", None
    if compression == "zstd":
        try:
            import zstandard
        except ImportError:
            raise ImportError("zstd compression needs the Python package zstandard "
                              "(python3-zstandard); use --compression lz4 or none") from None
        return "zstd", zstandard.ZstdCompressor(level=1).compress
    if compression == "lz4":
        try:
            import lz4.frame
        except ImportError:
            raise ImportError("lz4 compression needs the Python package lz4 (python3-lz4); "
                              "use --compression zstd or none") from None
        return "lz4", lz4.frame.compress
    raise ValueError(f"compression must be one of {', '.join(COMPRESSIONS)}, "
                     f"not {compression!r}")


# ---- schema text ------------------------------------------------------------------------------

def join_md_texts(parts: list[tuple[str, bytes]]) -> bytes:
    """A schema's data: for each (md name, definition text), the line `--- NAME` and the text;
    the topic's md first, then everything it imports."""
    out = []
    for name, text in parts:
        out += [SCHEMA_MARK, name.encode(), b"\n", text]
        if text and not text.endswith(b"\n"):
            out.append(b"\n")
    return b"".join(out)


def split_md_texts(data: bytes) -> list[tuple[str, bytes]]:
    """The (md name, definition text) pairs of a schema's data; ValueError if it does not
    start with a `--- NAME` line."""
    if not data.startswith(SCHEMA_MARK):
        raise ValueError("an ln-md-text schema starts with a line '--- MD_NAME'")
    starts = [0] + [m.start() + 1 for m in re.finditer(b"\n" + re.escape(SCHEMA_MARK), data)]
    parts: list[tuple[str, bytes]] = []
    for start, end in zip(starts, [*starts[1:], len(data)], strict=True):
        line_end = data.find(b"\n", start, end)
        line_end = end if line_end < 0 else line_end
        name = data[start + len(SCHEMA_MARK):line_end].decode()
        parts.append((name, data[line_end + 1:end]))
    return parts


def md_schema_text(md_name: str, md_dirs: list[str] | None = None) -> bytes:
    """The ln-md-text schema of md `md_name` as ln_generate finds it (the directories given
    to ln.add_message_definition_dir first, or `md_dirs`): its file and those it imports."""
    from ln_generate import MdRegistry, default_md_dirs

    from . import md_loader

    extra = md_dirs if md_dirs is not None else list(md_loader._extra_dirs)
    md = MdRegistry(default_md_dirs(extra)).load(md_name)
    return join_md_texts([(m.name, m.path.read_bytes()) for m in [md, *md.dependencies()]])


def write_md_files(schema: bytes, directory: str | os.PathLike[str]) -> list[str]:
    """Write the mds of an ln-md-text schema as md files below `directory` (an md directory
    for ln_generate or ln.add_message_definition_dir); their names.  ValueError for a name
    that would leave the directory."""
    names = []
    for name, text in split_md_texts(schema):
        parts = name.split("/")
        if not name or name.startswith("/") or any(p in ("", ".", "..") for p in parts):
            raise ValueError(f"md name {name!r} in the schema is not a relative md name")
        path = Path(directory, *parts)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(text)
        names.append(name)
    return names


def schema_message_class(md_name: str, schema: bytes) -> Any:
    """The Python message class of `md_name` built from a recorded schema alone (no md
    directory is searched): decodes a file whose mds are not installed."""
    from ln_generate import MdRegistry
    from ln_generate.emit_python import emit

    with tempfile.TemporaryDirectory(prefix="ln_schema.") as tmp:
        write_md_files(schema, tmp)
        md = MdRegistry([Path(tmp)]).load(md_name)
        source = emit([md], Path(f"<recorded md {md_name}>"), "recorded")
    namespace: dict[str, Any] = {"__name__": f"links_and_nodes.recorded.{md_name}"}
    exec(compile(source, f"<recorded md {md_name}>", "exec"), namespace)
    return namespace["MESSAGES"][md_name]


# ---- writer -----------------------------------------------------------------------------------

class SealedChunk(NamedTuple):
    """A chunk closed for new messages, not written yet: its records (uncompressed), the
    Message Index entries per channel and its first and last log time."""

    raw: bytearray
    indexes: list[tuple[int, bytes]]
    t0: int
    t1: int


class McapWriter:
    """Writes one MCAP file of ln topics.  Not thread-safe: callers serialize.

    compression: "zstd" (default), "lz4" or "none", per chunk.  chunk_size: a chunk is
    compressed and written once its messages reach this many bytes (or on flush()).
    Raises OSError if the file cannot be written (FileExistsError if it exists and not
    overwrite), ValueError / ImportError for a bad or unavailable compression."""

    def __init__(self, path: str | os.PathLike[str], compression: str = "zstd",
                 chunk_size: int = DEFAULT_CHUNK_SIZE, *,
                 writer_name: str = "links_and_nodes", overwrite: bool = True) -> None:
        self._compression, self._compress = _compressor(compression)
        if chunk_size < 1:
            raise ValueError(f"chunk_size must be positive, not {chunk_size}")
        self.path = Path(path)
        self.chunk_size = chunk_size
        flags = os.O_WRONLY | os.O_CREAT | os.O_CLOEXEC | (os.O_TRUNC if overwrite else os.O_EXCL)
        self._fd: int | None = os.open(self.path, flags, 0o644)
        self.offset = 0  # bytes in the file
        self._schemas: dict[tuple[str, str, bytes], int] = {}
        self._schema_records: list[bytes] = []
        self._channel_records: list[bytes] = []
        self._channel_counts: dict[int, int] = {}
        self._chunk_indexes: list[bytes] = []
        self._chunk = bytearray()
        self._index: dict[int, bytearray] = {}  # per channel: entries of the open chunk
        self._t0 = self._t1 = 0  # log times of the open chunk
        self.message_count = 0
        self.chunk_count = 0
        self._start = self._end = 0
        try:
            self._write(MAGIC + _record(HEADER, _s("") + _s(writer_name)))
        except BaseException:
            self._abandon()
            raise

    @property
    def pending(self) -> int:
        """Bytes of messages in the open chunk (not in the file yet)."""
        return len(self._chunk)

    def add_topic(self, topic: str, md_name: str, md_text: bytes | str, layout_hash: int,
                  message_size: int) -> int:
        """Register a topic recorded as raw ln bytes: its channel id for write().  md_text:
        the ln-md-text schema (md_schema_text()); topics of one md with the same text share a
        schema.  The schema and channel records go to the file at once."""
        text = md_text.encode() if isinstance(md_text, str) else bytes(md_text)
        return self.add_channel(topic, schema_name=md_name, schema_encoding=SCHEMA_ENCODING,
                                schema_data=text, message_encoding=MESSAGE_ENCODING,
                                metadata=ln_metadata(md_name, layout_hash, message_size))

    @property
    def channel_ids(self) -> frozenset[int]:
        """The ids of the channels registered so far."""
        return frozenset(self._channel_counts)

    def add_channel(self, topic: str, *, schema_name: str, schema_encoding: str,
                    schema_data: bytes, message_encoding: str,
                    metadata: dict[str, str], channel_id: int | None = None) -> int:
        """Register a channel of any encoding (ros2msg/cdr, jsonschema/json, a service's
        calls, one copied from another file): its id for write().  Equal schemas (name,
        encoding, data) are written once.  channel_id: this id (a copy of another file's
        channel whose chunks copy_chunk() copies); ValueError if it is taken or not a
        uint16 above 0.  Default: one more than the highest id so far."""
        if channel_id is not None and (not 0 < channel_id <= 0xFFFF
                                       or channel_id in self._channel_counts):
            raise ValueError(f"channel id {channel_id} is taken or out of range")
        key = (schema_name, schema_encoding, bytes(schema_data))
        records = b""
        schema_id = self._schemas.get(key)
        if schema_id is None:
            schema_id = len(self._schemas) + 1
            self._schemas[key] = schema_id
            rec = _record(SCHEMA, _U16.pack(schema_id) + _s(schema_name) + _s(schema_encoding)
                          + _U32.pack(len(key[2])) + key[2])
            self._schema_records.append(rec)
            records += rec
        channel = channel_id if channel_id is not None else max(self._channel_counts,
                                                                 default=0) + 1
        rec = _record(CHANNEL, _U16.pack(channel) + _U16.pack(schema_id) + _s(topic)
                      + _s(message_encoding) + _str_map(metadata))
        self._channel_records.append(rec)
        self._channel_counts[channel] = 0
        self._index[channel] = bytearray()
        self._write(records + rec)
        return channel

    def write(self, channel: int, seq: int, publish_time_ns: int, data: Any) -> None:
        """Append one sample (`data`: bytes-like, the raw message).  The MCAP sequence keeps
        the low 32 bits of `seq`; log and publish time are both `publish_time_ns`."""
        chunk = self._chunk
        index = self._index[channel]  # KeyError: not a channel of add_topic()
        offset = len(chunk)
        if offset:
            if publish_time_ns < self._t0:
                self._t0 = publish_time_ns
            elif publish_time_ns > self._t1:
                self._t1 = publish_time_ns
        else:
            self._t0 = self._t1 = publish_time_ns
        chunk += _MSG.pack(MESSAGE, 22 + len(data), channel, seq & 0xFFFFFFFF,
                           publish_time_ns, publish_time_ns)
        chunk += data
        index += _IDX.pack(publish_time_ns, offset)
        if len(chunk) >= self.chunk_size:
            self.flush()

    def flush(self) -> None:
        """Compress the open chunk and write it with its message indexes (one write)."""
        sealed = self._seal()
        if sealed is not None:
            self._finish_chunk(sealed)

    def _seal(self) -> SealedChunk | None:
        """The open chunk, taken out of the writer (a new one is open), or None if empty."""
        raw = self._chunk
        if not raw:
            return None
        indexes = [(channel, bytes(entries)) for channel, entries in self._index.items()
                   if entries]
        for entries in self._index.values():
            entries.clear()
        self._chunk = bytearray()
        return SealedChunk(raw, indexes, self._t0, self._t1)

    def _finish_chunk(self, sealed: SealedChunk) -> None:
        """Compress a sealed chunk and write it with its message indexes (one write)."""
        raw = sealed.raw
        data = self._compress(raw) if self._compress is not None else raw
        head = _CHUNK_HEAD.pack(sealed.t0, sealed.t1, len(raw), zlib.crc32(raw)) + _s(
            self._compression) + _U64.pack(len(data))
        head = _REC.pack(CHUNK, len(head) + len(data)) + head
        self._put_chunk(head, data, sealed.indexes, sealed.t0, sealed.t1,
                        self._compression, len(data), len(raw))

    def copy_chunk(self, chunk: RawChunk) -> None:
        """Append a Chunk record of another file as stored (compressed, with its CRC) after
        the open chunk: its Message Index records and Chunk Index get this file's offsets,
        the statistics its messages.  Its channels must be channels of this writer with the
        same ids (add_channel(channel_id=...)); ValueError otherwise or for a chunk without
        Message Index records.  Its messages keep their log times."""
        if not chunk.indexes:
            raise ValueError("a chunk without Message Index records cannot be copied")
        unknown = sorted(set(chunk.indexes) - set(self._channel_counts))
        if unknown:
            raise ValueError(f"the chunk has messages on channels {unknown}, which are not "
                             "channels of this writer")
        self.flush()
        self._put_chunk(chunk.head, chunk, chunk.indexes.items(), chunk.start_ns,
                        chunk.end_ns, chunk.compression, chunk.compressed_size,
                        chunk.uncompressed_size)

    def _put_chunk(self, head: bytes, data: Any, indexes: Any, t0: int, t1: int,
                   compression: str, compressed_size: int, uncompressed_size: int) -> None:
        """Write a chunk record (`head` and `data`, its rest, or a RawChunk to copy) and
        the Message Index records of `indexes` ((channel, entries) pairs) in one write (a
        copy: three); add its Chunk Index."""
        start = self.offset
        chunk_length = len(head) + (data.body_size if isinstance(data, RawChunk)
                                    else len(data))
        records = []
        index_offsets = b""
        at = start + chunk_length
        count = 0
        for channel, entries in indexes:
            if not entries:
                continue
            rec = _record(MESSAGE_INDEX, _U16.pack(channel) + _U32.pack(len(entries))
                          + bytes(entries))
            index_offsets += _U16.pack(channel) + _U64.pack(at)
            records.append(rec)
            at += len(rec)
            n = len(entries) // _IDX.size
            self._channel_counts[channel] += n
            count += n
        if isinstance(data, RawChunk):
            self._write(head)
            assert self._fd is not None, "the writer is closed"
            data.copy_body(self._fd)
            self.offset += data.body_size
            self._write(b"".join(records))
        else:
            self._write(head, data, b"".join(records))
        self._chunk_indexes.append(_record(CHUNK_INDEX, struct.pack(
            "<QQQQ", t0, t1, start, chunk_length)
            + _U32.pack(len(index_offsets)) + index_offsets
            + _U64.pack(at - start - chunk_length) + _s(compression)
            + struct.pack("<QQ", compressed_size, uncompressed_size)))
        if not self.message_count or t0 < self._start:
            self._start = t0
        self._end = max(self._end, t1)
        self.message_count += count
        self.chunk_count += 1

    def close(self) -> None:
        """Write the last chunk, the summary (schemas, channels, statistics, chunk indexes)
        and the footer, and close the file (idempotent)."""
        if self._fd is None:
            return
        try:
            self.flush()
            self._write(_record(DATA_END, _U32.pack(0)))  # 0: chunks carry their own CRCs
            self._write_summary()
        finally:
            self._abandon()

    def _write_summary(self) -> None:
        start = self.offset
        counts = b"".join(_U16.pack(c) + _U64.pack(n) for c, n in self._channel_counts.items())
        stats = _record(STATISTICS, struct.pack(
            "<QHIIIIQQ", self.message_count, len(self._schemas), len(self._channel_records),
            0, 0, self.chunk_count, self._start, self._end) + _U32.pack(len(counts)) + counts)
        groups = [(SCHEMA, b"".join(self._schema_records)),
                  (CHANNEL, b"".join(self._channel_records)), (STATISTICS, stats),
                  (CHUNK_INDEX, b"".join(self._chunk_indexes))]
        summary = b""
        offsets = b""
        for opcode, data in groups:
            if data:
                offsets += _record(SUMMARY_OFFSET, struct.pack(
                    "<BQQ", opcode, start + len(summary), len(data)))
                summary += data
        summary += offsets
        footer_head = _REC.pack(FOOTER, 20) + struct.pack(
            "<QQ", start, start + len(summary) - len(offsets))
        crc = zlib.crc32(footer_head, zlib.crc32(summary))
        self._write(summary, footer_head + _U32.pack(crc) + MAGIC)

    def _write(self, *parts: Any) -> None:
        """Write `parts` (bytes-like) in one system call where the kernel takes them all."""
        assert self._fd is not None, "the writer is closed"
        total = sum(len(p) for p in parts)
        done = os.writev(self._fd, parts)
        if done < total:  # a short write (a signal, a full disk): the rest one by one
            rest = memoryview(b"".join(bytes(p) for p in parts))[done:]
            while rest:
                rest = rest[os.write(self._fd, rest):]
        self.offset += total

    def _abandon(self) -> None:
        fd, self._fd = self._fd, None
        if fd is not None:
            os.close(fd)

    def __enter__(self) -> McapWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


# ---- reader -----------------------------------------------------------------------------------

class McapError(Exception):
    """A file that is not a readable MCAP recording: says which file, where and what."""

    def __init__(self, path: str | os.PathLike[str], offset: int, what: str) -> None:
        super().__init__(f"{path}: at byte {offset}: {what}")
        self.path, self.offset, self.what = str(path), offset, what


class McapTruncatedError(McapError):
    """The file ends inside a record: it was cut short (a recorder killed mid-write)."""


@dataclass(frozen=True)
class TopicInfo:
    """A recorded ln channel (a topic, or a service's calls): the md its samples have and how
    they are encoded.  `md_text` is the ln-md-text of the md and what it imports: the schema
    of an "ln-md" channel, the `md_text` metadata entry of other encodings ("" if absent)."""

    topic: str
    channel_id: int
    md_name: str
    md_text: bytes
    layout_hash: int
    message_size: int
    message_encoding: str = MESSAGE_ENCODING
    schema_name: str = ""
    schema_encoding: str = SCHEMA_ENCODING
    schema_data: bytes = b""
    metadata: dict[str, str] = field(default_factory=dict, compare=False, hash=False)

    @property
    def kind(self) -> str:
        """"topic", or what the channel's `kind` metadata says (e.g. "service")."""
        return self.metadata.get("kind", "topic")


class Sample(NamedTuple):
    topic: str
    md_name: str
    layout_hash: int
    seq: int  # the recorded low 32 bits, unwrapped per topic (monotonic within a file)
    publish_time_ns: int
    data: bytes


class _Skipped(NamedTuple):
    """A chunk's body left in the file: its first bytes, its size, the file."""

    prefix: bytes
    size: int
    file: Any


_SKIP_PREFIX = 256  # of a chunk body: enough for its header fields

Message = tuple["TopicInfo", int, int, Any]  # channel, 32-bit sequence, publish time, data


class _Bad(Exception):
    """Malformed content inside a record; the reader adds file and offset."""


class _Cursor:
    __slots__ = ("buf", "pos")

    def __init__(self, buf: bytes | memoryview) -> None:
        self.buf, self.pos = buf, 0

    def take(self, n: int) -> bytes:
        if n > len(self.buf) - self.pos:
            raise _Bad(f"a field needs {n} bytes but only {len(self.buf) - self.pos} are left")
        data = bytes(self.buf[self.pos:self.pos + n])
        self.pos += n
        return data

    def u(self, fmt: struct.Struct) -> int:
        return int(fmt.unpack(self.take(fmt.size))[0])

    def string(self) -> str:
        try:
            return self.take(self.u(_U32)).decode()
        except UnicodeDecodeError as exc:
            raise _Bad(f"a string is not UTF-8: {exc}") from None

    def str_map(self) -> dict[str, str]:
        inner = _Cursor(self.take(self.u(_U32)))
        out = {}
        while inner.pos < len(inner.buf):
            key = inner.string()
            out[key] = inner.string()
        return out


def _decompress(compression: str, data: bytes, size: int) -> bytes:
    if compression == "":
        return data
    try:
        if compression == "zstd":
            import zstandard

            return zstandard.ZstdDecompressor().decompress(data, max_output_size=size)
        if compression == "lz4":
            import lz4.frame

            return bytes(lz4.frame.decompress(data))
    except ImportError as exc:
        raise _Bad(f"{compression} chunks need the Python package {exc.name} "
                   f"(python3-{'zstandard' if compression == 'zstd' else 'lz4'})") from None
    except Exception as exc:  # the libraries' own error classes
        raise _Bad(f"the {compression} data of the chunk is corrupt: {exc}") from None
    raise _Bad(f"unknown chunk compression {compression!r}")


class McapReader:
    """Reads an MCAP recording in one pass, checking framing, lengths and CRCs; anything
    malformed raises McapError with file, byte offset and what is wrong.

    A file that ends cleanly after a record but without summary and footer (a recorder that
    was killed) is read to its end (`complete` is then False).  One that ends inside a
    record raises McapTruncatedError, unless allow_truncated: then everything before that
    record is read and `truncated_at` is its offset.  Channels without ln metadata (written
    by other tools) are skipped; samples come as stored, in their channel's encoding
    (record.encodings turns them into ln bytes)."""

    def __init__(self, path: str | os.PathLike[str], *, allow_truncated: bool = False) -> None:
        self.path = str(path)
        self.allow_truncated = allow_truncated
        self.complete = False  # a footer was read (after a full pass)
        self.truncated_at: int | None = None
        self._topics: dict[int, TopicInfo] = {}
        self._foreign: set[int] = set()  # channels without ln metadata
        self._scanned = False  # a full pass has been made: _topics holds every channel
        self.writer_library = ""  # the Header's library field: which program wrote the file
        self._schemas: dict[int, tuple[str, str, bytes]] = {}

    def channel(self, channel_id: int) -> TopicInfo | None:
        """The ln channel `channel_id` as far as the pass has read the file; None for one
        not (yet) defined or not an ln channel."""
        return self._topics.get(channel_id)

    def topics(self) -> dict[str, TopicInfo]:
        """The ln topics of the file by name, from its summary when it has one, else from a
        full pass."""
        infos = None if self._scanned else self._summary_topics()
        if infos is None:
            if not self._scanned:
                for _ in self.samples(topics=()):
                    pass
            infos = list(self._topics.values())
        return {info.topic: info for info in infos}

    def __iter__(self) -> Iterator[Sample]:
        return self.samples()

    def samples(self, topics: Any = None) -> Iterator[Sample]:
        """Every sample of the file in file order (each topic's in its recorded order); only
        those of `topics` (names) when given."""
        for _info, sample in self.items(topics):
            yield sample

    def items(self, topics: Any = None) -> Iterator[tuple[TopicInfo, Sample]]:
        """samples(), each with its channel."""
        wanted = None if topics is None else set(topics)
        last: dict[int, int] = {}
        self._scanned = False
        for info, seq, t_ns, data in self._messages():
            if wanted is not None and info.topic not in wanted:
                continue
            prev = last.get(info.channel_id)
            if prev is not None:
                seq |= prev & ~0xFFFFFFFF
                if seq < prev - (1 << 31):
                    seq += 1 << 32
            last[info.channel_id] = seq
            yield info, Sample(info.topic, info.md_name, info.layout_hash, seq, t_ns,
                               bytes(data))
        self._scanned = True

    def blocks(self) -> Iterator[RawChunk | Message]:
        """The data section in one pass, checked like samples() but chunks not decompressed:
        each Chunk as a RawChunk (give it to chunk_messages() for its messages, or copy
        it), each Message outside chunks as (channel, sequence, publish time, data).
        Schema and Channel records update channel() as they come (inside a chunk: once
        chunk_messages() has read it)."""
        self._topics = {}
        self._foreign = set()
        self.complete = False
        self.truncated_at = None
        schemas: dict[int, tuple[str, str, bytes]] = {}
        self._schemas = schemas
        held: RawChunk | None = None
        records = self._records()
        while True:
            try:
                pos, opcode, body = next(records)
            except StopIteration:
                break
            except McapError:
                if held is not None:  # what came before the bad record
                    yield replace(held, indexed=False)
                raise
            if opcode == MESSAGE_INDEX and held is not None:
                index = index_record(body)
                if index is None:  # not used for reading: only the chunk is not copyable
                    held = replace(held, indexed=False)
                else:
                    held.indexes[index[0]] = index[1]
                continue
            if held is not None:
                yield held
                held = None
            if opcode is not None:  # None: the end of the data section
                block = self._top_record(pos, opcode, body, schemas)
                if isinstance(block, RawChunk):
                    held = block
                elif block is not None:
                    yield block
        if held is not None:  # the file ends after it: its indexes may be cut short
            yield replace(held, indexed=False)

    def _top_record(self, pos: int, opcode: int, body: bytes,
                    schemas: dict[int, tuple[str, str, bytes]]) -> RawChunk | Message | None:
        """A record of the data section outside chunks: a chunk or message to yield, or a
        definition taken in (None)."""
        try:
            if opcode == CHUNK:
                return self._raw_chunk(pos, body, indexed=True)
            if opcode == MESSAGE:
                return self._message(body)
            if opcode in (SCHEMA, CHANNEL):
                self._definition(opcode, body, schemas)
            elif opcode == HEADER:
                self.writer_library = _header_library(body)
        except _Bad as exc:
            raise self._fail(pos, f"{_NAMES.get(opcode, opcode)} record: {exc}") from None
        return None

    def chunk_messages(self, chunk: RawChunk) -> Iterator[Message]:
        """The messages of `chunk` (one of blocks()) on ln channels, decompressed and checked
        (CRC, framing); McapError at the chunk's offset if they are not right."""
        try:
            yield from self._chunk(chunk, self._schemas)
        except _Bad as exc:
            raise self._fail(chunk.offset, f"Chunk record: {exc}") from None

    # -- the pass -----------------------------------------------------------------------------
    def _fail(self, offset: int, what: str) -> McapError:
        return McapError(self.path, offset, what)

    def _messages(self) -> Iterator[Message]:
        for block in self.blocks():
            if isinstance(block, RawChunk):
                yield from self.chunk_messages(block)
            else:
                yield block

    def _records(self) -> Iterator[tuple[int, int | None, bytes]]:
        """(offset, opcode, body) of each record of the data section, framing and the data
        CRC checked; opcode None once for its end (DATA_END or the footer)."""
        try:
            # a small buffer: a chunk left in the file is not read into it
            f = open(self.path, "rb", buffering=1 << 16)  # noqa: SIM115 - closed below
        except OSError as exc:
            raise McapError(self.path, 0, f"cannot open: {exc.strerror}") from None
        with f:
            size = os.fstat(f.fileno()).st_size
            if not self._magic(f):
                return
            crc: int | None = zlib.crc32(MAGIC)
            if _stated_data_crc(f, size) == 0:
                crc = None  # the DATA_END the footer leads to carries no CRC: none to compute
            pos, in_data, first = len(MAGIC), True, True
            while True:
                if pos == size:
                    return  # no footer: a recording that was not closed
                head = self._frame(f, pos, size, first)
                if head is None:
                    return
                first = False
                opcode, length = _REC.unpack(head)
                name = _NAMES.get(opcode, f"opcode 0x{opcode:02x}")
                body = self._body(f, opcode, length, crc)
                try:
                    if opcode == DATA_END:
                        if in_data:
                            _check_data_crc(body, crc)
                            yield pos, None, b""
                        in_data = False
                    elif opcode == FOOTER:
                        self._footer(f, pos, body, size)
                        if in_data:
                            yield pos, None, b""
                        return
                    elif in_data:
                        if crc is not None:
                            crc = zlib.crc32(body, zlib.crc32(head, crc))
                        yield pos, opcode, body
                        f.seek(pos + _REC.size + length)
                except _Bad as exc:
                    raise self._fail(pos, f"{name} record: {exc}") from None
                pos += _REC.size + length

    def _body(self, f: Any, opcode: int, length: int, crc: int | None) -> Any:
        """The body of a record (bytes); of a chunk when no CRC needs its bytes, only its
        start (the header fields) and where the rest is (_Skipped)."""
        if opcode != CHUNK or crc is not None or length <= _SKIP_PREFIX:
            return f.read(length)
        prefix = f.read(_SKIP_PREFIX)
        name = _U32.unpack_from(prefix, _CHUNK_HEAD.size)[0]
        if _CHUNK_HEAD.size + 4 + name + 8 > len(prefix):  # a long compression name
            return prefix + f.read(length - _SKIP_PREFIX)
        return _Skipped(prefix, length, f)

    def _frame(self, f: Any, pos: int, size: int, first: bool) -> bytes | None:
        """The opcode and length of the record at `pos`, checked to fit the file; None where
        the file ends inside it (allow_truncated)."""
        head = f.read(_REC.size)
        if len(head) < _REC.size:
            self._truncated(pos, f"the file ends {len(head)} bytes into a record header")
            return None
        opcode, length = _REC.unpack(head)
        name = _NAMES.get(opcode, f"opcode 0x{opcode:02x}")
        if first and opcode != HEADER:
            raise self._fail(pos, f"the first record is {name}, not a Header")
        if length > size - pos - _REC.size:
            self._truncated(pos, f"{name} record of {length} bytes, but the file ends "
                            f"{size - pos - _REC.size} bytes after its header")
            return None
        return head

    def _magic(self, f: Any) -> bool:
        """Read the magic at the start: False for a file cut short inside it."""
        magic = f.read(len(MAGIC))
        if magic != MAGIC[:len(magic)] or len(magic) == 0:
            raise self._fail(0, "not an MCAP file (no MCAP magic at the start)")
        if len(magic) < len(MAGIC):
            self._truncated(0, "the file ends inside the MCAP magic")
            return False
        return True

    def _truncated(self, offset: int, what: str) -> None:
        if not self.allow_truncated:
            raise McapTruncatedError(self.path, offset, f"truncated: {what}")
        self.truncated_at = offset

    def _footer(self, f: Any, pos: int, body: bytes, size: int) -> None:
        if len(body) != 20:
            raise _Bad(f"{len(body)} bytes, not 20")
        end = f.read(len(MAGIC) + 1)
        if end[:len(MAGIC)] != MAGIC or pos + _REC.size + 20 + len(MAGIC) != size:
            raise _Bad("not followed by the closing MCAP magic at the end of the file")
        self.complete = True

    def _raw_chunk(self, pos: int, body: bytes | _Skipped, indexed: bool) -> RawChunk:
        skipped = body if isinstance(body, _Skipped) else None
        size = len(body) if skipped is None else skipped.size
        cur = _Cursor(body if skipped is None else skipped.prefix)  # type: ignore[arg-type]
        t0, t1, usize, ucrc = _CHUNK_HEAD.unpack(cur.take(_CHUNK_HEAD.size))
        compression = cur.string()
        n = cur.u(_U64)
        if n != size - cur.pos:
            raise _Bad(f"its records field says {n} bytes, the record holds "
                       f"{size - cur.pos}")
        if skipped is not None:
            return RawChunk(pos, _REC.pack(CHUNK, size), size, t0, t1, usize, ucrc,
                            compression, cur.pos, {}, indexed, None, skipped.file)
        return RawChunk(pos, _REC.pack(CHUNK, size), size, t0, t1, usize, ucrc, compression,
                        cur.pos, {}, indexed, body)  # type: ignore[arg-type]

    def _chunk(self, chunk: RawChunk, schemas: dict[int, tuple[str, str, bytes]]
               ) -> Iterator[Message]:
        usize, ucrc = chunk.uncompressed_size, chunk.uncompressed_crc
        raw = _decompress(chunk.compression, memoryview(chunk.body)[chunk.data_at:], usize)
        if len(raw) != usize:
            raise _Bad(f"{len(raw)} bytes uncompressed, the chunk says {usize}")
        if ucrc and zlib.crc32(raw) != ucrc:
            raise _Bad(f"CRC of the uncompressed records 0x{zlib.crc32(raw):08x} is not "
                       f"the chunk's 0x{ucrc:08x}")
        at = 0
        view = memoryview(raw)
        topics, unpack_rec, unpack_msg = self._topics, _REC.unpack_from, _MSG_BODY.unpack_from
        rec_size, msg_end = _REC.size, _REC.size + _MSG_BODY.size
        while at < usize:
            if usize - at < rec_size:
                raise _Bad(f"a record header at offset {at} of the records runs past their end")
            opcode, length = unpack_rec(raw, at)
            end = at + rec_size + length
            if end > usize:
                raise _Bad(f"the record at offset {at} of the records ({length} bytes) runs "
                           "past their end")
            if opcode == MESSAGE and length >= _MSG_BODY.size:
                channel, seq, _log_time, t_ns = unpack_msg(raw, at + rec_size)
                info = topics.get(channel)
                if info is not None and (end - at - msg_end == info.message_size
                                         or info.message_encoding != MESSAGE_ENCODING):
                    yield info, seq, t_ns, view[at + msg_end:end]
                    at = end
                    continue
            try:  # the rare cases, and the errors
                if opcode == MESSAGE:
                    msg = self._message(view[at + rec_size:end])
                    if msg is not None:
                        yield msg
                elif opcode in (SCHEMA, CHANNEL):
                    self._definition(opcode, view[at + rec_size:end], schemas)
            except _Bad as exc:
                raise _Bad(f"{_NAMES.get(opcode, opcode)} at offset {at} of the records: "
                           f"{exc}") from None
            at = end

    def _message(self, body: Any) -> tuple[TopicInfo, int, int, bytes] | None:
        """The sample of a Message record; None on a channel that is not an ln topic."""
        if len(body) < _MSG_BODY.size:
            raise _Bad(f"{len(body)} bytes, shorter than a message header")
        channel, seq, _log_time, t_ns = _MSG_BODY.unpack_from(body)
        info = self._topics.get(channel)
        if info is None:
            if channel in self._foreign:
                return None
            raise _Bad(f"a message on channel {channel}, which no Channel record before it "
                       "defines")
        data = bytes(body[_MSG_BODY.size:])
        if len(data) != info.message_size and info.message_encoding == MESSAGE_ENCODING:
            raise _Bad(f"a sample of topic '{info.topic}' has {len(data)} bytes, its md "
                       f"'{info.md_name}' {info.message_size}")
        return info, seq, t_ns, data

    def _definition(self, opcode: int, body: Any,
                    schemas: dict[int, tuple[str, str, bytes]]) -> None:
        cur = _Cursor(body)
        if opcode == SCHEMA:
            sid = cur.u(_U16)
            name, encoding = cur.string(), cur.string()
            schemas[sid] = (name, encoding, cur.take(cur.u(_U32)))
            return
        info = _channel_info(cur, schemas)
        if info is None:
            self._foreign.add(_U16.unpack_from(body)[0])
        else:
            self._topics[info.channel_id] = info

    def _summary_topics(self) -> list[TopicInfo] | None:
        """The topics from the summary section, or None where there is none to read."""
        try:
            with open(self.path, "rb") as f:
                size = os.fstat(f.fileno()).st_size
                tail = _REC.size + 20 + len(MAGIC)
                if size < len(MAGIC) + tail:
                    return None
                f.seek(size - tail)
                data = f.read(tail)
                opcode, length = _REC.unpack_from(data)
                if data[-len(MAGIC):] != MAGIC or opcode != FOOTER or length != 20:
                    return None
                start = _U64.unpack_from(data, _REC.size)[0]
                if not len(MAGIC) <= start <= size - tail:
                    return None
                f.seek(start)
                summary = f.read(size - tail - start)
        except OSError:
            return None
        schemas: dict[int, tuple[str, str, bytes]] = {}
        infos = []
        at = 0
        try:
            while at + _REC.size <= len(summary):
                opcode, length = _REC.unpack_from(summary, at)
                body = summary[at + _REC.size:at + _REC.size + length]
                if opcode == SCHEMA:
                    self._definition(SCHEMA, body, schemas)
                elif opcode == CHANNEL:
                    info = _channel_info(_Cursor(body), schemas)
                    if info is not None:
                        infos.append(info)
                at += _REC.size + length
        except _Bad:
            return None  # a full pass says what is wrong
        return infos


def _stated_data_crc(f: Any, size: int) -> int | None:
    """The CRC of the DATA_END record just before the summary the footer points to (0: the
    writer computed none); None where there is no such record.  Leaves `f` at the data."""
    tail = _REC.size + 20 + len(MAGIC)
    found = None
    if size >= 2 * len(MAGIC) + tail + _REC.size + 4:
        f.seek(size - tail)
        data = f.read(tail)
        summary = _U64.unpack_from(data, _REC.size)[0]
        if (data[-len(MAGIC):] == MAGIC and _REC.unpack_from(data) == (FOOTER, 20)
                and len(MAGIC) + _REC.size + 4 <= summary <= size - tail):
            f.seek(summary - _REC.size - 4)
            end = f.read(_REC.size + 4)
            if _REC.unpack_from(end) == (DATA_END, 4):
                found = _U32.unpack_from(end, _REC.size)[0]
    f.seek(len(MAGIC))
    return found


def _check_data_crc(data_end: bytes, crc: int | None) -> None:
    expected = _Cursor(data_end).u(_U32)
    if expected and crc is not None and expected != crc:
        raise _Bad(f"data section CRC 0x{expected:08x} does not match its bytes (0x{crc:08x})")


def _header_library(body: bytes) -> str:
    """The library field of a Header record ("" where it cannot be read)."""
    try:
        cur = _Cursor(body)
        cur.string()
        return cur.string()
    except _Bad:
        return ""


def _channel_info(cur: _Cursor, schemas: dict[int, tuple[str, str, bytes]]
                  ) -> TopicInfo | None:
    """The TopicInfo of a Channel record; None for a channel that is not an ln channel (its
    metadata has no md_name)."""
    channel, schema_id = cur.u(_U16), cur.u(_U16)
    topic, encoding = cur.string(), cur.string()
    meta = cur.str_map()
    if "md_name" not in meta:
        return None
    schema = schemas.get(schema_id)
    if schema is None:
        raise _Bad(f"channel {channel} ('{topic}') uses schema {schema_id}, which no Schema "
                   "record before it defines")
    name, schema_encoding, text = schema
    try:
        md_name = meta["md_name"]
        layout_hash = int(meta["layout_hash"], 16)
        message_size = int(meta["message_size"])
    except (KeyError, ValueError) as exc:
        raise _Bad(f"channel {channel} ('{topic}') lacks valid ln metadata "
                   f"(md_name, layout_hash, message_size): {exc}") from None
    if encoding == MESSAGE_ENCODING:
        if schema_encoding != SCHEMA_ENCODING or name != md_name:
            raise _Bad(f"channel {channel} ('{topic}') of md '{md_name}' has schema '{name}' "
                       f"of encoding '{schema_encoding}', not '{SCHEMA_ENCODING}'")
        md_text = text
    else:
        md_text = meta.get("md_text", "").encode()
    return TopicInfo(topic, channel, md_name, md_text, layout_hash, message_size, encoding,
                     name, schema_encoding, text, meta)


def iter_mcap(path: str | os.PathLike[str], topics: Any = None, *,
              allow_truncated: bool = True) -> Iterator[Sample]:
    """(topic, md_name, layout_hash, seq, publish_time_ns, data) of every sample in the file,
    in file order; only those of `topics` when given.  A file cut short inside a record is
    read up to that record (allow_truncated=False: McapTruncatedError instead)."""
    return McapReader(path, allow_truncated=allow_truncated).samples(topics)


def read_topics(path: str | os.PathLike[str]) -> dict[str, TopicInfo]:
    """The recorded topics of the file, each with its md name, md text, layout hash, size."""
    return McapReader(path, allow_truncated=True).topics()
