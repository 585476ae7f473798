"""bench/network/network_report.py on made-up records: CPU per MB, medians that skip a
figure a system has not, ratios against raw TCP per host, and every goal of issue 36
passing, missing, or n/a while the multi-host system is not there."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import pytest

REPO = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(REPO / "bench" / "network"))
import network_report as nr  # noqa: E402

MIB = nr.MIB
Record = dict[str, Any]


def thr(
    system: str,
    mb_per_s: float,
    cpu_a: float | None,
    cpu_b: float | None,
    lost: int = 0,
    size: int = MIB,
) -> Record:
    """A throughput run of `size` that delivered 1,000 samples at `mb_per_s`, with CPU
    seconds `cpu_a` / `cpu_b` on the hosts."""
    rate = mb_per_s * 1e6 / size
    sent = {"sent": 1000 + lost, "elapsed_s": 1.0, "cpu_s": 0.0}
    got = {"received": 1000, "elapsed_s": 999 / rate}
    paced = 0.7 * rate if system in nr.PACE else None
    return {
        "round": 0,
        "kind": "throughput",
        "size": size,
        "system": system,
        **nr.throughput_stats(sent, got, size, {"a": cpu_a, "b": cpu_b}, paced),
    }


def lat(system: str, p50: float, size: int = MIB) -> Record:
    return {
        "round": 0,
        "kind": "latency",
        "size": size,
        "system": system,
        "p50_us": p50,
        "p99_us": p50,
        "p999_us": p50,
        "max_us": p50,
        "resent": 0,
    }


def by_goal(rows: list[Record]) -> dict[str, Record]:
    return {g["goal"]: g for g in rows}


def test_size_labels() -> None:
    assert [nr.size_label(s) for s in (64, 64 << 10, 1 << 20, 4 << 20, 4096 + 1)] == [
        "64 B",
        "64 KiB",
        "1 MiB",
        "4 MiB",
        "4097 B",
    ]


def test_cpu_per_mb_is_microseconds_per_delivered_megabyte() -> None:
    assert nr.cpu_per_mb(0.5, 1_000_000_000) == pytest.approx(500.0)
    assert nr.cpu_per_mb(0.5, 0) is None
    assert nr.cpu_per_mb(None, 1_000_000) is None


def test_throughput_stats_carries_cpu_and_pace() -> None:
    rec = nr.throughput_stats(
        {"sent": 10, "elapsed_s": 0.1},
        {"received": 8, "elapsed_s": 0.7},
        MIB,
        {"a": 0.01, "b": None},
        100.0,
    )
    assert rec["lost"] == 2
    assert rec["msgs_per_s"] == pytest.approx(10.0)
    assert rec["cpu_a_us_per_mb"] == pytest.approx(0.01 * 1e6 / (8 * MIB / 1e6))
    assert rec["cpu_b_us_per_mb"] is None
    assert rec["paced_msgs_per_s"] == 100.0
    plain = nr.throughput_stats({"sent": 1, "elapsed_s": 0}, {"received": 1, "elapsed_s": 0}, 64)
    assert plain["msgs_per_s"] == 0.0 and plain["cpu_a_us_per_mb"] is None


def test_summary_medians_skip_missing_figures() -> None:
    runs = [
        thr("ln_local", 100, 1.0, None),
        thr("ln_local", 300, 3.0, None),
        thr("ln_local", 200, 2.0, None),
    ]
    (rec,) = nr.summarize(runs)
    assert rec["mb_per_s"] == pytest.approx(200)
    assert (rec["low"], rec["high"]) == pytest.approx((100, 300))
    assert rec["cpu_a_us_per_mb"] == pytest.approx(2.0 * 1e6 / (1000 * MIB / 1e6))
    assert rec["cpu_b_us_per_mb"] is None


def test_cpu_ratios_per_host_and_one_host_against_both() -> None:
    raw = {"system": "raw_tcp", "cpu_a_us_per_mb": 100.0, "cpu_b_us_per_mb": 200.0}
    ln = {"system": "ln_tcp", "cpu_a_us_per_mb": 150.0, "cpu_b_us_per_mb": 500.0}
    local = {"system": "ln_local", "cpu_a_us_per_mb": 600.0, "cpu_b_us_per_mb": None}
    assert nr.cpu_ratios(ln, raw) == pytest.approx((1.5, 2.5))
    assert nr.cpu_ratios(local, raw) == (pytest.approx(2.0), None)
    assert nr.cpu_ratios(ln, None) == (None, None)


def complete_runs() -> list[Record]:
    """Every 1 MiB and 64 B case: ln over TCP meets its goals, ln over UDP misses each
    large one (p50, MB/s, a lost sample, CPU on b)."""
    return [
        lat("raw_udp", 20.0, 64),
        lat("raw_tcp", 20.0, 64),
        lat("ln_udp", 39.0, 64),
        lat("ln_tcp", 41.0, 64),
        lat("raw_tcp", 400.0),
        lat("ln_tcp", 520.0),
        lat("ln_udp", 801.0),
        thr("raw_tcp", 2000, 1.0, 1.0),
        thr("ln_tcp", 1400, 1.4, 1.4),
        thr("ln_udp", 990, 1.0, 1.0),
        thr("ln_tcp_paced", 1400, 1.4, 1.4),
        thr("ln_udp_paced", 1000, 0.5, 2.5, lost=1),
    ]


def test_goals_pass_and_miss_on_their_limits() -> None:
    summary = nr.summarize(complete_runs())
    paced = nr.find(summary, "throughput", MIB, "ln_udp_paced")
    assert paced is not None
    assert (paced["cpu_a_x_raw"], paced["cpu_b_x_raw"]) == pytest.approx((0.5, 2.5))
    goals = by_goal(nr.goals(summary))
    tcp, udp = "ln a->b, TCP", "ln a->b, UDP"
    expect = {
        f"{udp} 64 B p50 <= 1.5x raw UDP + 10 µs": ("PASS", 39 / 20),
        f"{tcp} 64 B p50 <= 1.5x raw TCP + 10 µs": ("MISS", 41 / 20),
        f"{tcp} 1 MiB p50 <= 1.3x raw TCP": ("PASS", 1.3),
        f"{tcp} 1 MiB MB/s delivered at the goal rate >= 0.7x raw TCP": ("PASS", 0.7),
        f"{tcp} at 0.7x raw TCP's msg/s, 1 MiB: lost == 0": ("PASS", 0.7),
        f"{tcp} at 0.7x raw, 1 MiB: cpu a <= 2x raw TCP's": ("PASS", 1.4),
        f"{tcp} at 0.7x raw, 1 MiB: cpu b <= 2x raw TCP's": ("PASS", 1.4),
        f"{udp} 1 MiB p50 <= 2x raw TCP": ("MISS", 801 / 400),
        f"{udp} 1 MiB MB/s delivered at the goal rate >= 0.5x raw TCP": ("PASS", 0.5),
        f"{udp} at 0.5x raw, 1 MiB: cpu a <= 2x raw TCP's": ("PASS", 0.5),
        f"{udp} at 0.5x raw, 1 MiB: cpu b <= 2x raw TCP's": ("MISS", 2.5),
    }
    assert set(goals) == set(expect)
    for name, (verdict, ratio) in expect.items():
        assert (goals[name]["verdict"], goals[name]["ratio"]) == (verdict, pytest.approx(ratio)), (
            name
        )
    assert goals[f"{tcp} 64 B p50 <= 1.5x raw TCP + 10 µs"]["limit_us"] == pytest.approx(40.0)
    assert goals[f"{tcp} at 0.7x raw TCP's msg/s, 1 MiB: lost == 0"]["measured"] == (
        "lost 0 of 1000"
    )


def test_goals_without_multihost_are_not_applicable() -> None:
    runs = [r for r in complete_runs() if not r["system"].startswith("ln_")]
    runs += [
        {"round": 0, "kind": k, "size": s, "system": sys_, "unavailable": "no forwarding"}
        for k, cases in (("latency", nr.LATENCY_CASES), ("throughput", nr.THROUGHPUT_CASES))
        for s, sys_ in cases
        if sys_ in nr.TRANSPORT
    ]
    rows = nr.goals(nr.summarize(runs))
    assert rows and {g["verdict"] for g in rows} == {"n/a"}
    assert all("no forwarding" in line for line in nr.goals_table(rows)[2:])


def test_tables_show_every_size_and_system() -> None:
    runs = complete_runs() + [
        thr("raw_tcp", 3000, 0.5, 0.5, size=4 * MIB),
        {"round": 0, "kind": "throughput", "size": 4 * MIB, "system": "ln_tcp", "error": "boom"},
    ]
    summary = nr.summarize(runs)
    text = "\n".join(nr.throughput_tables(summary, {64 << 10: 20000, MIB: 2000, 4 * MIB: 500}))
    for label in (
        "64 KiB: 20,000 samples",
        "1 MiB: 2,000 samples",
        "4 MiB: 500 samples",
        "ln a->b, TCP at 0.7x raw",
        "ln a->b, UDP at 0.5x raw",
        "error: boom",
        "cpu a µs/MB",
    ):
        assert label in text
    lines = text.splitlines()
    mib = lines.index("1 MiB: 2,000 samples")
    row = next(line for line in lines[mib:] if line.startswith("ln a->b, UDP at"))
    assert row.split()[-3:] == ["2,384", "2.50", "1"]  # cpu b µs/MB, x raw, rounds
    goals_text = "\n".join(nr.goals_table(nr.goals(summary)))
    assert "lost 0 of 1000" in goals_text and "MISS" in goals_text and "PASS" in goals_text
