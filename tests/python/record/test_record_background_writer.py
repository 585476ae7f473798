"""record/background_writer.py: the writer ln_record uses, whose chunks are compressed and
written on a thread of its own, writes byte for byte the file McapWriter writes for the same
calls (a channel added between chunks, a copied chunk, every compression), keeps at most
IN_FLIGHT chunks in flight, and raises the writer thread's failure at the next call."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from links_and_nodes.mcap_format import McapReader, McapWriter, RawChunk
from links_and_nodes.record import background_writer
from links_and_nodes.record.background_writer import IN_FLIGHT, BackgroundMcapWriter

T0 = 1_700_000_000_000_000_000


def payload(i: int, size: int) -> bytes:
    return (i.to_bytes(4, "little") * (size // 4 + 1))[:size]


def drive(out: McapWriter, copied: RawChunk | None) -> None:
    """The same calls for either writer: two channels, the second added after chunks were
    sealed, a flush, a copied chunk, more samples."""
    a = out.add_topic("t.a", "bw/a", b"--- bw/a\n", 0xA, 64)
    for i in range(300):
        out.write(a, i + 1, T0 + i * 1000, payload(i, 64))
    b = out.add_topic("t.b", "bw/b", b"--- bw/b\n", 0xB, 64)
    for i in range(300, 700):
        out.write(a if i % 2 else b, i + 1, T0 + i * 1000, payload(i, 64))
    out.flush()
    if copied is not None:
        out.copy_chunk(copied)
    for i in range(700, 800):
        out.write(b, i + 1, T0 + i * 1000, payload(i, 64))


def a_chunk_to_copy(tmp_path: Path, compression: str) -> tuple[RawChunk, Iterator[Any]]:
    """The first chunk of another file, and the reader's block iterator, which keeps the
    file open (the chunk's body is copied from it)."""
    src = tmp_path / "src.mcap"
    with McapWriter(src, compression, 1 << 20) as out:
        drive(out, None)
    blocks = McapReader(src).blocks()
    return next(b for b in blocks if isinstance(b, RawChunk)), blocks


@pytest.mark.parametrize("compression", ["none", "zstd", "lz4"])
def test_writes_what_the_plain_writer_writes(tmp_path: Path, compression: str) -> None:
    copied, _open = a_chunk_to_copy(tmp_path, compression)
    plain, background = tmp_path / "plain.mcap", tmp_path / "background.mcap"
    with McapWriter(plain, compression, 4000) as out:
        drive(out, copied)
    with BackgroundMcapWriter(background, compression, 4000) as out:
        drive(out, copied)
    assert plain.read_bytes() == background.read_bytes()
    assert len(list(McapReader(background).samples())) == 800 + _count(copied)


def _count(chunk: RawChunk) -> int:
    """Messages of a chunk: its Message Index entries (16 bytes each)."""
    return sum(len(entries) // 16 for entries in chunk.indexes.values())


def test_at_most_in_flight_chunks_wait(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """While the writer thread is held, flushes queue up to IN_FLIGHT chunks, then wait."""
    import threading

    gate = threading.Event()
    finish = BackgroundMcapWriter._finish_chunk

    def held(self: BackgroundMcapWriter, sealed: Any) -> None:
        gate.wait()
        finish(self, sealed)

    monkeypatch.setattr(BackgroundMcapWriter, "_finish_chunk", held)
    out = BackgroundMcapWriter(tmp_path / "x.mcap", "none", 100)
    ch = out.add_topic("t", "bw/a", b"--- bw/a\n", 0xA, 200)
    for i in range(IN_FLIGHT):
        out.write(ch, i + 1, T0 + i, payload(i, 200))  # each fills and seals a chunk
    assert len(out._flying) == IN_FLIGHT and out.chunk_count == 0
    assert out.pending >= IN_FLIGHT * 200
    blocked = threading.Thread(target=out.write, args=(ch, 99, T0 + 99, payload(99, 200)))
    blocked.start()
    blocked.join(0.2)
    assert blocked.is_alive()  # the third sealed chunk waits for the oldest
    gate.set()
    blocked.join(10)
    assert not blocked.is_alive()
    out.close()
    assert [m.seq for m in McapReader(tmp_path / "x.mcap").samples()] == [1, 2, 99]


def test_a_failed_chunk_write_is_raised_at_the_next_call(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    out = BackgroundMcapWriter(tmp_path / "x.mcap", "none", 100)
    ch = out.add_topic("t", "bw/a", b"--- bw/a\n", 0xA, 200)

    def full_disk(fd: int, parts: Any) -> int:
        raise OSError(28, os.strerror(28))

    monkeypatch.setattr(background_writer.McapWriter, "_write",
                        lambda self, *parts: full_disk(0, parts))
    out.write(ch, 1, T0, payload(1, 200))  # sealed and handed over
    with pytest.raises(OSError, match="No space left"):
        out.close()
    assert out._fd is None  # closed all the same: no descriptor left behind
