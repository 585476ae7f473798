"""The MCAP mapping without a manager: McapWriter's files as the PyPI `mcap` reader and
@mcap/core (TypeScript) read them, our reader on files of the PyPI writer, the schema text
that carries an md with its imports, sequence wrap-around, and what the reader says about
cut-short and corrupt files."""

from __future__ import annotations

import ctypes
import struct
from pathlib import Path

import pytest

import links_and_nodes as ln
from links_and_nodes.mcap_format import (
    COMPRESSIONS,
    McapError,
    McapReader,
    McapTruncatedError,
    McapWriter,
    iter_mcap,
    md_schema_text,
    read_topics,
    schema_message_class,
    split_md_texts,
)

from .conftest import pypi_mcap, pypi_messages, pypi_stream
from .mcap_js import js_read
from .recording import chunk_offsets

SAMPLE = ln.message_class("rectest/sample")
TOOL = ln.message_class("rectest/tool")


def sample_bytes(i: int) -> bytes:
    msg = SAMPLE()
    msg.counter = i
    msg.value = i * 0.5
    msg.values[:] = [i, -i, i * 3, 7]
    return bytes(msg)


def write_file(path: Path, compression: str, n: int = 600, chunk_size: int = 2000,
               first_seq: int = 1) -> list[tuple[str, int, int, bytes]]:
    """Two topics, `n` samples of rectest/sample and n/3 of rectest/tool; what was written."""
    written = []
    with McapWriter(path, compression, chunk_size) as out:
        a = out.add_topic("rec.a", "rectest/sample", md_schema_text("rectest/sample"),
                          SAMPLE.LAYOUT_HASH, ctypes.sizeof(SAMPLE))
        b = out.add_topic("rec.b", "rectest/tool", md_schema_text("rectest/tool"),
                          TOOL.LAYOUT_HASH, ctypes.sizeof(TOOL))
        for i in range(n):
            t = 1_700_000_000_000_000_000 + i * 1000
            out.write(a, first_seq + i, t, sample_bytes(i))
            written.append(("rec.a", first_seq + i, t, sample_bytes(i)))
            if i % 3 == 0:
                tool = TOOL()
                tool.counter = i
                tool.tcp.position[:] = [i, 2, 3]
                out.write(b, i // 3 + 1, t + 1, bytes(tool))
                written.append(("rec.b", i // 3 + 1, t + 1, bytes(tool)))
    return written


@pytest.mark.parametrize("compression", COMPRESSIONS)
def test_files_read_alike_by_three_readers(tmp_path: Path, compression: str) -> None:
    path = tmp_path / f"x_{compression}.mcap"
    written = write_file(path, compression)
    ours = [(s.topic, s.seq, s.publish_time_ns, s.data) for s in iter_mcap(path)]
    assert ours == written
    assert pypi_messages(path) == written
    # the PyPI seeking reader: summary, statistics and chunk indexes
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None and summary.statistics.message_count == len(written)
        assert summary.statistics.channel_message_counts == {1: 600, 2: 200}
        by_index = sorted((c.topic, m.sequence, m.publish_time, bytes(m.data))
                          for _, c, m in reader.iter_messages())
    assert by_index == sorted(written)
    js = js_read(path)[str(path)]
    assert js["done"] and js["leftover"] == 0
    assert js["indexed"]["messages"] == js["indexed"]["statistics"] == len(written)
    assert [(t, seq, int(p), bytes.fromhex(d)) for t, seq, p, _, d in js["messages"]] == written
    assert [c["metadata"] for c in js["channels"]] == [
        {"md_name": "rectest/sample", "layout_hash": f"{SAMPLE.LAYOUT_HASH:016x}",
         "message_size": str(ctypes.sizeof(SAMPLE))},
        {"md_name": "rectest/tool", "layout_hash": f"{TOOL.LAYOUT_HASH:016x}",
         "message_size": str(ctypes.sizeof(TOOL))}]
    assert {c["encoding"] for c in js["channels"]} == {"ln-md"}
    assert {s["encoding"] for s in js["schemas"].values()} == {"ln-md-text"}


def test_schema_carries_the_md_and_its_imports(tmp_path: Path) -> None:
    path = tmp_path / "tool.mcap"
    write_file(path, "zstd", n=30)
    info = read_topics(path)["rec.b"]
    parts = split_md_texts(info.md_text)
    assert [name for name, _ in parts] == ["rectest/tool", "robot/pose", "rectest/stamp"]
    assert parts[0][1] == (Path(__file__).parent / "md" / "rectest" / "tool").read_bytes()
    # decoded from the file alone: the same layout, the same values
    cls = schema_message_class(info.md_name, info.md_text)
    assert cls.LAYOUT_HASH == info.layout_hash == TOOL.LAYOUT_HASH
    sample = next(s for s in iter_mcap(path, topics=["rec.b"]) if s.seq == 4)
    assert cls.from_buffer_copy(sample.data).to_dict() == TOOL.from_buffer_copy(
        sample.data).to_dict()
    assert cls.from_buffer_copy(sample.data).tcp.position.tolist() == [9.0, 2.0, 3.0]


def test_sequence_keeps_low_32_bits_and_reader_unwraps(tmp_path: Path) -> None:
    path = tmp_path / "wrap.mcap"
    first = (1 << 32) - 100
    write_file(path, "none", n=300, first_seq=first)
    stored = [m[1] for m in pypi_messages(path) if m[0] == "rec.a"]
    assert stored[:100] == list(range(first, 1 << 32)) and stored[100:] == list(range(200))
    assert [s.seq for s in iter_mcap(path, topics=["rec.a"])] == list(range(first, first + 300))


def test_reads_what_the_pypi_writer_wrote(tmp_path: Path) -> None:
    """Schemas and channels inside chunks, channel ids from 1, a foreign (json) channel."""
    pypi_mcap()
    from mcap.writer import CompressionType, Writer

    path = tmp_path / "pypi.mcap"
    with open(path, "wb") as f:
        writer = Writer(f, compression=CompressionType.LZ4, chunk_size=500)
        writer.start()
        other = writer.register_channel("json.topic", "json",
                                        writer.register_schema("x", "jsonschema", b"{}"))
        sid = writer.register_schema("rectest/sample", "ln-md-text",
                                     md_schema_text("rectest/sample"))
        ch = writer.register_channel("rec.a", "ln-md", sid, {
            "md_name": "rectest/sample", "layout_hash": f"{SAMPLE.LAYOUT_HASH:016x}",
            "message_size": str(ctypes.sizeof(SAMPLE))})
        for i in range(50):
            writer.add_message(other, i, b'{"i": 1}', i, sequence=i)
            writer.add_message(ch, 10 + i, sample_bytes(i), 10 + i, sequence=i + 1)
        writer.finish()
    got = list(iter_mcap(path))
    assert [(s.topic, s.seq, s.publish_time_ns, s.data) for s in got] == [
        ("rec.a", i + 1, 10 + i, sample_bytes(i)) for i in range(50)]
    assert list(read_topics(path)) == ["rec.a"]


def test_a_file_cut_anywhere_reads_up_to_its_last_complete_record(tmp_path: Path) -> None:
    path = tmp_path / "full.mcap"
    written = write_file(path, "zstd", n=900)
    data = path.read_bytes()
    chunks = chunk_offsets(path)
    assert len(chunks) > 5
    per_chunk = []
    for off, length in chunks:
        cut = tmp_path / "cut.mcap"
        cut.write_bytes(data[:off + length])
        per_chunk.append(len(list(iter_mcap(cut))))
    for k, (off, length) in enumerate(chunks[1:], 1):
        for cut_at in (off + 1, off + 9, off + length // 2, off + length - 1):
            cut = tmp_path / "cut.mcap"
            cut.write_bytes(data[:cut_at])
            reader = McapReader(cut, allow_truncated=True)
            got = [(s.topic, s.seq, s.publish_time_ns, s.data) for s in reader]
            assert got == written[:per_chunk[k - 1]]  # everything of the complete chunks
            assert reader.truncated_at == off and not reader.complete
            with pytest.raises(McapTruncatedError, match=f"at byte {off}: truncated"):
                list(McapReader(cut))
            records, done = pypi_stream(cut)
            assert not done
            assert sum(1 for r in records if type(r).__name__ == "Message") == per_chunk[k - 1]


@pytest.mark.parametrize("what", ["payload", "crc", "magic", "length", "header"])
def test_corrupt_files_are_refused_with_offset_and_reason(tmp_path: Path, what: str) -> None:
    path = tmp_path / "bad.mcap"
    write_file(path, "none", n=300)
    data = bytearray(path.read_bytes())
    off, length = chunk_offsets(path)[2]
    if what == "payload":  # a byte of a sample: the chunk's CRC no longer matches
        data[off + length - 5] ^= 0xFF
        expected = rf"at byte {off}: Chunk record: CRC of the uncompressed records"
    elif what == "crc":
        struct.pack_into("<I", data, off + 9 + 24, 12345)
        expected = rf"at byte {off}: Chunk record: CRC"
    elif what == "magic":
        data[0:4] = b"GIF8"
        expected = r"at byte 0: not an MCAP file"
    elif what == "length":  # a record length that runs past a later record boundary
        struct.pack_into("<Q", data, off + 1, length - 9 + 3)
        expected = rf"at byte {off}: Chunk record: its records field says"
    else:
        data[8] = 0x05
        expected = r"at byte 8: the first record is Message, not a Header"
    path.write_bytes(bytes(data))
    with pytest.raises(McapError, match=expected) as info:
        list(McapReader(path, allow_truncated=True))
    assert info.value.path == str(path)
