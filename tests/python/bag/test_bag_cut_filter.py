"""ln_bag cut keeps exactly start <= publish time <= end in each time syntax; filter keeps
the selected topics; outputs read back with the PyPI mcap reader."""

from __future__ import annotations

from datetime import UTC, datetime
from pathlib import Path

from bag.conftest import T0, messages, run_bag


def _iso(ns: int) -> str:
    s = datetime.fromtimestamp(ns // 10**9, UTC).strftime("%Y-%m-%dT%H:%M:%S")
    return f"{s}.{ns % 10**9:09d}Z"


def test_cut_keeps_boundaries_in_every_syntax(tmp_path: Path, two_topics) -> None:
    src, samples = two_topics
    lo, hi = T0 + 250_000_000, T0 + 1_005_000_000  # both are sample times
    assert any(t == lo for _, _, t in samples) and any(t == hi for _, _, t in samples)
    expected = [(topic, seq, t) for topic, seq, t in samples if lo <= t <= hi]
    first = min(t for _, _, t in samples)
    syntaxes = [(str(lo), str(hi)), (_iso(lo), _iso(hi)),
                (f"+{(lo - first) / 1e9}", f"{(hi - first) / 1e9}s")]
    for k, (start, end) in enumerate(syntaxes):
        out = tmp_path / f"cut{k}.mcap"
        assert run_bag("cut", src, "-o", out, "--start", start, "--end", end, "-q") == 0
        got = [(topic, seq, t) for topic, seq, t, _ in messages(out)]
        assert got == expected, (start, end)


def test_cut_one_side_and_empty_range(tmp_path: Path, two_topics) -> None:
    src, samples = two_topics
    out = tmp_path / "tail.mcap"
    assert run_bag("cut", src, "-o", out, "--start", "+1.5", "-q") == 0
    assert [m[2] for m in messages(out)] == [t for _, _, t in samples if t >= T0 + 1_500_000_000]
    out2 = tmp_path / "none.mcap"
    assert run_bag("cut", src, "-o", out2, "--start", "+100", "-q") == 0
    assert messages(out2) == []


def test_cut_usage_errors(tmp_path: Path, two_topics, capsys) -> None:
    src, _ = two_topics
    assert run_bag("cut", src, "-o", tmp_path / "x.mcap") == 2
    assert run_bag("cut", src, "-o", tmp_path / "x.mcap", "--start", "+2", "--end", "+1") == 2
    assert "is before --start" in capsys.readouterr().err


def test_filter_topics_regex_exclude(tmp_path: Path, two_topics) -> None:
    src, samples = two_topics
    cases = {("--topic", "a.state"): {"a.state"}, ("--regex", r"b\..*"): {"b.cmd"},
             ("--exclude", "a.*"): {"b.cmd"}, ("--regex", ".*", "--exclude", "b.cmd"): {"a.state"}}
    original = messages(src)
    for k, (argv, topics) in enumerate(cases.items()):
        out = tmp_path / f"f{k}.mcap"
        assert run_bag("filter", src, "-o", out, *argv, "-q") == 0
        assert messages(out) == [m for m in original if m[0] in topics]
