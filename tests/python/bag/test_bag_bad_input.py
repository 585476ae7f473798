"""ln_bag on bad input: a cut-short or corrupt file gives `FILE: at byte N: what`, exit 1,
and a finished output with the samples before the bad record; an output that is an input or
exists is refused."""

from __future__ import annotations

import os
from pathlib import Path

from bag.conftest import messages, pypi_stream, run_bag, write_recording
from links_and_nodes.mcap_format import iter_mcap


def _readable_prefix(path: Path) -> list[tuple[str, int, int, bytes]]:
    return [(s.topic, s.seq, s.publish_time_ns, s.data) for s in iter_mcap(path)]


def test_truncated_input(tmp_path: Path, two_topics, capsys) -> None:
    src, _ = two_topics
    data = src.read_bytes()
    cut = tmp_path / "short.mcap"
    cut.write_bytes(data[: len(data) // 2])
    before = _readable_prefix(cut)  # allow_truncated: up to the record cut in two
    assert 0 < len(before) < len(messages(src))
    for command in (["filter", "--exclude", "none"], ["cut", "--start", "0"],
                    ["convert", "--encoding", "ln"]):
        out = tmp_path / f"{command[0]}.mcap"
        assert run_bag(command[0], cut, "-o", out, *command[1:], "-q") == 1
        err = capsys.readouterr().err
        assert f"{cut}: at byte " in err and "truncated" in err
        _, complete = pypi_stream(out)
        assert complete
        assert messages(out) == before
    assert run_bag("info", cut, "-q") == 1
    assert "cut short" in capsys.readouterr().out


def test_corrupt_input(tmp_path: Path, two_topics, capsys) -> None:
    src, _ = two_topics
    data = bytearray(src.read_bytes())
    bad = tmp_path / "bad.mcap"
    at = len(data) // 2
    data[at] ^= 0xFF
    bad.write_bytes(data)
    assert run_bag("merge", bad, "-o", tmp_path / "m.mcap", "-q") == 1
    err = capsys.readouterr().err
    assert f"{bad}: at byte " in err
    offset = int(err.split("at byte ")[1].split(":")[0])
    assert offset <= at
    got = messages(tmp_path / "m.mcap")
    assert got == messages(src)[: len(got)]


def test_output_is_input_or_exists(tmp_path: Path, two_topics, capsys) -> None:
    src, _ = two_topics
    size = src.stat().st_size
    link = tmp_path / "link.mcap"
    os.link(src, link)
    for out in (src, link):
        assert run_bag("filter", src, "-o", out, "-x", "a.state", "--force") == 1
        assert "refusing to write over an input" in capsys.readouterr().err
    assert src.stat().st_size == size
    other = write_recording(tmp_path / "other.mcap", [("t", 1, 1)])
    assert run_bag("cut", src, "-o", other, "--start", "+1") == 1
    assert "exists: give --force" in capsys.readouterr().err
    assert run_bag("cut", src, "-o", other, "--start", "+1", "--force", "-q") == 0
    assert messages(other)
