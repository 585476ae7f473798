"""ln_bag merge: two hosts' pieces, overlapping and slightly out of order, become their
publish-time-sorted union without a repeated (topic, seq); split: the pieces one after the
other hold exactly the input's samples."""

from __future__ import annotations

from pathlib import Path

from bag.conftest import T0, messages, run_bag, write_recording
from links_and_nodes.mcap_format import iter_mcap


def test_merge_two_hosts(tmp_path: Path) -> None:
    a = [("arm.state", k, T0 + k * 1_000_000) for k in range(1, 301)]
    b = [("leg.state", k, T0 + k * 1_000_000 + 500) for k in range(1, 201)]
    # host 1 logged arm 1..200 and leg 1..100; host 2 arm 150..300 and leg 80..200; each
    # file interleaves its topics in blocks (out of publish order by up to 40 ms)
    host1 = a[:200][20:] + b[:100] + a[:20]
    host2 = b[79:] + a[149:]
    write_recording(tmp_path / "h1.mcap", host1, chunk_size=2048)
    write_recording(tmp_path / "h2.mcap", host2, compression="lz4", chunk_size=1024)
    out = tmp_path / "merged.mcap"
    assert run_bag("merge", tmp_path / "h1.mcap", tmp_path / "h2.mcap", "-o", out, "-q") == 0
    got = [(m[0], m[1], m[2]) for m in messages(out)]
    union = sorted(set(host1) | set(host2), key=lambda s: (s[2], s[0]))
    assert got == union
    assert len({(topic, seq) for topic, seq, _ in got}) == len(got) == 500


def test_merge_split_pieces_back(tmp_path: Path, two_topics) -> None:
    src, samples = two_topics
    assert run_bag("split", src, "-o", tmp_path / "p", "--size", "3000", "-q",
                   "--chunk-size", "1000") == 0
    pieces = sorted(tmp_path.glob("p_*.mcap"))
    assert len(pieces) > 2
    out = tmp_path / "back.mcap"
    assert run_bag("merge", *pieces, "-o", out, "-q") == 0
    assert messages(out) == messages(src)


def test_split_by_size_and_duration(tmp_path: Path, two_topics) -> None:
    src, samples = two_topics
    original = messages(src)
    assert run_bag("split", src, "-o", tmp_path / "s.mcap", "--size", "4KB", "-q") == 0
    pieces = sorted(tmp_path.glob("s_*.mcap"))
    assert len(pieces) >= 3
    assert [m for p in pieces for m in messages(p)] == original
    assert run_bag("split", src, "-o", tmp_path / "d", "--duration", "0.5", "-q") == 0
    pieces = sorted(tmp_path.glob("d_*.mcap"))
    assert len(pieces) == 5  # 0 .. 2.48 s of samples, 0.5 s each
    assert [m for p in pieces for m in messages(p)] == original
    for p in pieces:
        times = [s.publish_time_ns for s in iter_mcap(p)]
        assert max(times) - min(times) < 500_000_000
    assert run_bag("split", src, "-o", tmp_path / "d", "--duration", "0.5", "-q") == 1
