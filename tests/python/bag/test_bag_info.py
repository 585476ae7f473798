"""ln_bag info: counts, gaps, time ranges and bytes equal what the test computes from the
samples it wrote; services are listed apart; completeness is reported."""

from __future__ import annotations

import json
from pathlib import Path

from bag.conftest import T0, run_bag, write_recording


def _expected(samples: list[tuple[str, int, int]], topic: str) -> dict[str, int]:
    mine = [(seq, t) for name, seq, t in samples if name == topic]
    seqs = [s for s, _ in mine]
    gaps = sum(b - a - 1 for a, b in zip(seqs, seqs[1:], strict=False) if b > a + 1)
    return {"count": len(mine), "gaps": gaps, "first_ns": min(t for _, t in mine),
            "last_ns": max(t for _, t in mine), "bytes": 32 * len(mine)}


def _info(capsys, *paths: Path) -> tuple[int, dict]:
    capsys.readouterr()
    code = run_bag("info", *paths, "--json", "-q")
    return code, json.loads(capsys.readouterr().out)


def test_info_counts_gaps_and_services(tmp_path: Path, capsys) -> None:
    seqs = [s for s in range(1, 400) if s % 7 and s not in range(100, 130)]
    samples = [("arm.state", s, T0 + s * 1_000_000) for s in seqs]
    samples += [("arm.get_pose", s, T0 + s * 3_000_000 + 1) for s in (1, 2, 3, 9)]
    samples.sort(key=lambda x: x[2])
    path = write_recording(tmp_path / "r.mcap", samples, services=("arm.get_pose",))
    code, out = _info(capsys, path)
    assert code == 0
    f = out["files"][0]
    assert f["complete"] and f["summary"] and f["status"] == "complete"
    assert f["messages"] == len(samples) == f["summary_message_count"]
    assert f["compressions"] == {"zstd": f["chunks"]} and f["chunks"] > 1
    assert [t["topic"] for t in f["topics"]] == ["arm.state"]
    assert [s["topic"] for s in f["services"]] == ["arm.get_pose"]
    for entry in f["topics"] + f["services"]:
        got = {k: entry[k] for k in ("count", "gaps", "first_ns", "last_ns", "bytes")}
        assert got == _expected(samples, entry["topic"])
        assert entry["md_name"] == "rectest/sample" and entry["message_encoding"] == "ln-md"
    assert f["first_ns"] == min(t for *_, t in samples)
    assert f["last_ns"] == max(t for *_, t in samples)
    capsys.readouterr()
    assert run_bag("info", path) == 0
    text = capsys.readouterr().out
    gaps = _expected(samples, "arm.state")["gaps"]
    assert gaps == 52 + 30  # multiples of 7 up to 398 but 105..126, and 100..129
    assert "services:" in text and "arm.get_pose" in text and f"gaps {gaps}" in text


def test_info_of_a_file_without_summary(tmp_path: Path, capsys) -> None:
    samples = [("x", s, T0 + s) for s in range(1, 2001)]
    path = write_recording(tmp_path / "open.mcap", samples, compression="lz4", close=False)
    code, out = _info(capsys, path)
    f = out["files"][0]
    assert code == 0 and not f["complete"] and not f["summary"]
    assert f["status"].startswith("no summary")
    assert f["compressions"] == {"lz4": f["chunks"]}
    assert f["topics"][0]["count"] == 2000 and f["topics"][0]["gaps"] == 0
