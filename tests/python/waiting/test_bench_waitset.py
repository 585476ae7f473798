"""bench/waitset/bench_waitset.py in its quickest form: it runs against its own manager and
writes the table and the JSON with every case (or the reason one is missing), the idle pair
and the five goals of issue 29.  Only the structure is checked, never a measured figure."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from buildtree import build_dir

REPO = Path(__file__).resolve().parents[3]
SCRIPT = REPO / "bench" / "waitset" / "bench_waitset.py"
PROGRAM = build_dir() / "bench" / "waitset" / "waitset_bench"
CASES = (
    "read",
    "read0",
    "waitset1",
    "waitset10",
    "waitset100",
    "waitset1000",
    "py_read",
    "py_async",
)
SAMPLES = 40
LIMIT = 300.0  # seconds: an upper bound against hangs, never a pass criterion


def test_quick_run_writes_every_case_and_goal(tmp_path: Path) -> None:
    if not PROGRAM.exists():
        pytest.fail(f"{PROGRAM} is missing: run scons first")
    out = tmp_path / "waitset.json"
    done = subprocess.run(
        [
            sys.executable,
            str(SCRIPT),
            "--quick",
            "--samples",
            str(SAMPLES),
            "--warmup",
            "5",
            "--idle-seconds",
            "1",
            "--build-dir",
            str(build_dir()),
            "--json",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=LIMIT,
    )
    assert done.returncode == 0, done.stderr
    result = json.loads(out.read_text())
    assert result["quick"] is True
    assert result["errors"] == {}
    assert result["leftover_segments"] == []
    for case in CASES:
        if case == "py_async" and case in result["unavailable"]:
            assert "read_async" in result["unavailable"][case]
            continue
        stats = result["summary"][case]
        assert 0 < stats["samples"] <= SAMPLES
        assert stats["rounds"] == 1
        assert stats["inports"] == (int(case[7:]) if case.startswith("waitset") else 1)
        assert 0 < stats["p50_us"] <= stats["p90_us"] <= stats["p99_us"] <= stats["max_us"]
        assert stats["cpu_us_per_wait"] is not None
        assert len(result["runs"][case]) == 1
    for kind in ("waitset", "sleep"):
        idle = result["idle"][kind]
        assert idle["inports"] == 100
        assert idle["wall_s"] > 0 and idle["cpu_s"] >= 0
    assert isinstance(result["idle"]["waitset"]["timer_expiries"], int)
    assert result["idle"]["waitset"]["other_events"] == 0
    goals = result["goals"]
    assert len(goals) == 5
    for goal in goals:
        assert goal["status"] in ("PASS", "MISS", "MISSING")
        if goal["status"] == "MISSING":
            assert goal["why"] and "Python" in goal["goal"]
        else:
            assert goal["measured"] >= 0 and goal["baseline"] >= 0
    table = out.with_suffix(".txt").read_text()
    assert "C waitset" in table and "Python sub.read()" in table
    assert "idle process" in table and table.count("PASS") + table.count("MISS") >= 4
    assert done.stdout.startswith(table.splitlines()[0])
