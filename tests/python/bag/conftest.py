"""Fixtures of the ln_bag tests: recordings built directly with McapWriter (exact samples,
topics of the recording tests' mds), ln_bag run in-process, and the recording tests' `lab`
(a private manager) and PyPI `mcap` helpers for the files made by a real ln_record."""

from __future__ import annotations

import struct
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import pytest
from record.conftest import MD_DIR, lab, pypi_messages, pypi_stream  # noqa: F401

from links_and_nodes.bag.cli import main
from links_and_nodes.mcap_format import McapWriter, md_schema_text

SAMPLE_MD = "rectest/sample"  # uint64 counter, double value, int32 values[4]
SAMPLE_HASH = 0x31E316F3DE599ED1
T0 = 1_765_000_000_000_000_000


def sample_bytes(counter: int) -> bytes:
    return struct.pack("<Qd4i", counter, counter * 0.25, counter, -counter, 7, counter * 3)


def write_recording(path: Path, samples: Iterable[tuple[str, int, int]], *,
                    compression: str = "zstd", chunk_size: int = 4096,
                    services: tuple[str, ...] = (), close: bool = True) -> Path:
    """A recording of (topic, seq, publish time) samples of rectest/sample, in that order;
    topics in `services` get channel metadata kind=service."""
    text = md_schema_text(SAMPLE_MD, [str(MD_DIR)])
    w = McapWriter(path, compression, chunk_size)
    channels: dict[str, int] = {}
    for topic, seq, t in samples:
        if topic not in channels:
            extra = {"kind": "service"} if topic in services else {}
            channels[topic] = w.add_channel(
                topic, schema_name=SAMPLE_MD, schema_encoding="ln-md-text", schema_data=text,
                message_encoding="ln-md",
                metadata={"md_name": SAMPLE_MD, "layout_hash": f"{SAMPLE_HASH:016x}",
                          "message_size": "32", **extra})
        w.write(channels[topic], seq, t, sample_bytes(seq))
    if close:
        w.close()
    else:
        w.flush()
    return path


def messages(path: Path) -> list[tuple[str, int, int, bytes]]:
    """(topic, seq, publish time, data) by the PyPI reader, which checks CRCs."""
    return pypi_messages(path)


def run_bag(*argv: Any) -> int:
    return main([str(a) for a in argv])


@pytest.fixture
def two_topics(tmp_path: Path) -> tuple[Path, list[tuple[str, int, int]]]:
    """300 samples of a.state (every 10 ms) and b.cmd (every 25 ms), interleaved."""
    samples = [("a.state", k + 1, T0 + k * 10_000_000) for k in range(200)]
    samples += [("b.cmd", k + 1, T0 + 5_000_000 + k * 25_000_000) for k in range(100)]
    samples.sort(key=lambda s: s[2])
    return write_recording(tmp_path / "in.mcap", samples), samples
