"""The chunk-copy fast path of ln_bag: chunks whose samples are all kept go to the output
as stored (their bytes equal the input's), the rest sample by sample; either way the output
equals, sample for sample, what the per-sample path (another --compression) writes, and the
PyPI mcap readers (stream with CRCs, indexed through the summary) read it."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from bag.conftest import T0, pypi_stream, run_bag, write_recording
from links_and_nodes.mcap_format import McapReader, McapWriter, RawChunk

PER_CHUNK = 10  # samples of 63 record bytes: a chunk of 630 bytes holds 10
CHUNK_SIZE = 63 * PER_CHUNK


def _blocks(topics: list[str], chunks: int) -> list[tuple[str, int, int]]:
    """`chunks` chunks of PER_CHUNK samples each, the chunks' topics in turn."""
    out = []
    for c in range(chunks):
        for k in range(PER_CHUNK):
            n = c * PER_CHUNK + k
            out.append((topics[c % len(topics)], n + 1, T0 + n * 1_000_000))
    return out


def _mixed(chunks: int) -> list[tuple[str, int, int]]:
    """Every chunk holds both topics."""
    return [("a.state" if n % 2 else "b.cmd", n + 1, T0 + n * 1_000_000)
            for n in range(chunks * PER_CHUNK)]


def chunk_bodies(path: Path) -> list[bytes]:
    return [b.body for b in McapReader(path).blocks() if isinstance(b, RawChunk)]


def pypi_records(path: Path) -> list[tuple[int, str, int, int, int, bytes]]:
    """(channel id, topic, sequence, log time, publish time, data): stream reader, CRCs."""
    records, complete = pypi_stream(path)  # skips or fails first where mcap is missing
    from mcap.records import Channel, Message

    assert complete
    topics = {r.id: r.topic for r in records if isinstance(r, Channel)}
    return [(r.channel_id, topics[r.channel_id], r.sequence, r.log_time, r.publish_time,
             bytes(r.data)) for r in records if isinstance(r, Message)]


def check_indexed(path: Path) -> None:
    """The PyPI indexed reader: chunk indexes lead to the chunks and their message indexes,
    the statistics count what the file holds."""
    expected = pypi_records(path)
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        summary = reader.get_summary()
        assert summary is not None
        got = [(c.id, c.topic, m.sequence, m.log_time, m.publish_time, bytes(m.data))
               for _s, c, m in reader.iter_messages(log_time_order=False)]
        data = path.read_bytes()
        for index in summary.chunk_indexes:
            at = index.chunk_start_offset
            assert data[at] == 0x06  # a Chunk record
            assert int.from_bytes(data[at + 1:at + 9], "little") + 9 == index.chunk_length
            for _channel, offset in index.message_index_offsets.items():
                assert data[offset] == 0x07  # a Message Index record
    assert got == expected
    stats = summary.statistics
    assert stats is not None and stats.message_count == len(expected)
    counts: dict[int, int] = {}
    for rec in expected:
        counts[rec[0]] = counts.get(rec[0], 0) + 1
    assert {c: n for c, n in stats.channel_message_counts.items() if n} == counts
    if expected:
        assert stats.message_start_time == min(r[3] for r in expected)
        assert stats.message_end_time == max(r[3] for r in expected)


def _both(tmp_path: Path, src: Path, *argv: Any) -> tuple[Path, Path]:
    """The output of ln_bag `argv` on `src` with the default compression (that of the
    input: fast path) and with --compression none (the per-sample path)."""
    fast, slow = tmp_path / "fast.mcap", tmp_path / "slow.mcap"
    assert run_bag(argv[0], src, "-o", fast, *argv[1:], "-q") == 0
    assert run_bag(argv[0], src, "-o", slow, *argv[1:], "--compression", "none", "-q") == 0
    assert pypi_records(fast) == pypi_records(slow)
    check_indexed(fast)
    check_indexed(slow)
    assert chunk_bodies(slow) and not set(chunk_bodies(slow)) & set(chunk_bodies(src))
    return fast, slow


def test_cut_copies_the_chunks_inside_and_decodes_the_edges(tmp_path: Path) -> None:
    samples = _blocks(["a.state", "b.cmd"], 12)
    src = write_recording(tmp_path / "in.mcap", samples, chunk_size=CHUNK_SIZE)
    inputs = chunk_bodies(src)
    assert len(inputs) == 12
    lo, hi = samples[25][2], samples[84][2]  # inside chunk 2 and chunk 8
    fast, _ = _both(tmp_path, src, "cut", "--start", lo, "--end", hi)
    assert [(t, s, p) for _, t, s, _, p, _ in pypi_records(fast)] == [
        x for x in samples if lo <= x[2] <= hi]
    copied = set(chunk_bodies(fast)) & set(inputs)
    assert copied == set(inputs[3:8])  # chunks 3..7 whole, 2 and 8 cut at the edges


def test_filter_of_whole_topics_copies_their_chunks(tmp_path: Path) -> None:
    samples = _blocks(["a.state", "b.cmd", "c.odo"], 9)
    src = write_recording(tmp_path / "in.mcap", samples, chunk_size=CHUNK_SIZE)
    inputs = chunk_bodies(src)
    fast, _ = _both(tmp_path, src, "filter", "--topic", "a.state", "--topic", "c.odo")
    assert chunk_bodies(fast) == [b for k, b in enumerate(inputs) if k % 3 != 1]
    got = pypi_records(fast)
    assert [(t, s, p) for _, t, s, _, p, _ in got] == [x for x in samples if x[0] != "b.cmd"]
    ids = {t: c for c, t, *_ in pypi_records(src)}
    assert all(ids[t] == c for c, t, *_ in got)  # the input's channel ids


def test_filter_of_mixed_chunks_decodes_them(tmp_path: Path) -> None:
    samples = _mixed(6)
    src = write_recording(tmp_path / "in.mcap", samples, chunk_size=CHUNK_SIZE)
    fast, _ = _both(tmp_path, src, "filter", "--topic", "a.state")
    assert not set(chunk_bodies(fast)) & set(chunk_bodies(src))
    assert [(t, s, p) for _, t, s, _, p, _ in pypi_records(fast)] == [
        x for x in samples if x[0] == "a.state"]


@pytest.mark.parametrize("compression", ["zstd", "lz4", "none"])
def test_convert_to_the_same_encoding_copies_every_chunk(tmp_path: Path,
                                                         compression: str) -> None:
    samples = _mixed(5)
    src = write_recording(tmp_path / "in.mcap", samples, chunk_size=CHUNK_SIZE,
                          compression=compression)
    out = tmp_path / "out.mcap"
    assert run_bag("convert", src, "-o", out, "--encoding", "ln", "-q") == 0
    assert chunk_bodies(out) == chunk_bodies(src)
    assert pypi_records(out) == pypi_records(src)
    check_indexed(out)
    slow = tmp_path / "slow.mcap"
    other = "lz4" if compression != "lz4" else "zstd"
    assert run_bag("convert", src, "-o", slow, "--encoding", "ln", "--compression", other,
                   "-q") == 0
    assert pypi_records(slow) == pypi_records(out)


def test_a_different_compression_decodes_every_chunk(tmp_path: Path) -> None:
    src = write_recording(tmp_path / "in.mcap", _mixed(4), chunk_size=CHUNK_SIZE)
    out = tmp_path / "out.mcap"
    assert run_bag("filter", src, "-o", out, "--exclude", "none", "--compression", "lz4",
                   "-q") == 0
    assert not set(chunk_bodies(out)) & set(chunk_bodies(src))
    assert pypi_records(out) == pypi_records(src)


def test_a_file_without_summary_is_copied_up_to_its_last_chunk(tmp_path: Path,
                                                               capsys: Any) -> None:
    samples = _mixed(4)
    src = write_recording(tmp_path / "in.mcap", samples, chunk_size=CHUNK_SIZE, close=False)
    out = tmp_path / "out.mcap"
    assert run_bag("filter", src, "-o", out, "--exclude", "none") == 0
    # the last chunk's indexes might be cut short: it is decoded (its bytes come out the
    # same, so the count tells), the others copied
    assert "(3 chunks copied as stored)" in capsys.readouterr().err
    assert [(t, s, p) for _, t, s, _, p, _ in pypi_records(out)] == samples
    check_indexed(out)


def _register(w: McapWriter, reader: McapReader, chunk: RawChunk) -> list[int]:
    ids = []
    for c in sorted(chunk.indexes, reverse=True):
        info = reader.channel(c)
        assert info is not None
        ids.append(w.add_channel(info.topic, schema_name=info.schema_name,
                                 schema_encoding=info.schema_encoding,
                                 schema_data=info.schema_data,
                                 message_encoding=info.message_encoding,
                                 metadata=info.metadata, channel_id=c))
    return ids


def test_writer_copy_chunk_and_channel_ids(tmp_path: Path) -> None:
    src = write_recording(tmp_path / "in.mcap", _mixed(2), chunk_size=CHUNK_SIZE)
    reader = McapReader(src)
    w = McapWriter(tmp_path / "out.mcap", "zstd")
    bodies = []
    for chunk in reader.blocks():  # a chunk's bytes are read while the pass is at it
        assert isinstance(chunk, RawChunk)
        if not bodies:
            with pytest.raises(ValueError, match="not channels of this writer"):
                w.copy_chunk(chunk)
            ids = _register(w, reader, chunk)
            assert ids == sorted(chunk.indexes, reverse=True)
            with pytest.raises(ValueError, match="taken"):
                w.add_channel("x", schema_name="s", schema_encoding="e", schema_data=b"",
                              message_encoding="m", metadata={}, channel_id=ids[0])
            assert w.add_channel("y", schema_name="s", schema_encoding="e", schema_data=b"",
                                 message_encoding="m", metadata={}) == max(ids) + 1
        w.copy_chunk(chunk)
        bodies.append(chunk.body)
    w.close()
    assert len(bodies) == 2
    assert chunk_bodies(tmp_path / "out.mcap") == bodies == chunk_bodies(src)
    assert pypi_records(tmp_path / "out.mcap") == pypi_records(src)
    check_indexed(tmp_path / "out.mcap")


@pytest.mark.parametrize("how", [("--size", "2500"), ("--duration", "0.025")])
def test_split_copies_the_chunks_that_fit_a_piece(tmp_path: Path, how: tuple[str, str],
                                                  capsys: Any) -> None:
    samples = _mixed(10)
    src = write_recording(tmp_path / "in.mcap", samples, chunk_size=CHUNK_SIZE)
    assert run_bag("split", src, "-o", tmp_path / "piece", *how) == 0
    said = capsys.readouterr().err
    assert "ln_bag split: 100 samples into " in said
    pieces = sorted(tmp_path.glob("piece_*.mcap"))
    assert len(pieces) > 2
    got = []
    for piece in pieces:
        check_indexed(piece)
        got += pypi_records(piece)
    assert got == pypi_records(src)
    copied = int(said.split(" chunks copied as stored")[0].rsplit("(", 1)[1])
    assert copied >= 5
