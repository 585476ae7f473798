"""Benchmark of the protection of forwarded topics (issue 33, docs/security.md "Host-to-host
data"): 64 B one-way latency (p50) and 1 MiB throughput from host a to host b over UDP and TCP
with the instance's `security` at none, authenticate and encrypt, all in the same run in
alternating rounds (network namespaces, the lab of bench_network.py; run scons first; needs
root).  Goals: 64 B p50 with authenticate <= 1.1x and with encrypt <= 1.2x that of none;
1 MiB MB/s with encrypt >= 0.8x that of none.  Prints a table with the ratios and PASS/MISS,
writes bench/results/network_security.json and .md, exits 0 either way.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE.parent / "topics"))
sys.path.insert(0, str(REPO / "tests" / "python"))
for _p in (REPO, REPO / "python"):
    if str(_p) not in sys.path:
        sys.path.insert(0, str(_p))
sys.path.insert(0, str(HERE))  # bench_network.py here, not tests/python/bench_network

from bench_network import Bench  # noqa: E402
from netlab import NetLab, netlab_available  # noqa: E402
from network_cases import CaseError, Lab  # noqa: E402

LEVELS = ("none", "authenticate", "encrypt")
SYSTEMS = ("ln_udp", "ln_tcp")
MIB = 1 << 20
LAT_GOAL = {"authenticate": 1.1, "encrypt": 1.2}  # 64 B p50 at most this many times none's
THR_GOAL = {"encrypt": 0.8}  # 1 MiB MB/s at least this many times none's
ROUNDS, QUICK_ROUNDS = 5, 2
Record = dict[str, Any]


def measure(bench: Bench, lab: Lab, rounds: int) -> list[Record]:
    cases = [
        (kind, system, level)
        for kind in ("latency", "throughput")
        for system in SYSTEMS
        for level in LEVELS
    ]
    runs: list[Record] = []
    for rnd in range(rounds):
        print(f"round {rnd + 1}/{rounds}", file=sys.stderr, flush=True)
        k = rnd % len(cases)
        for kind, system, level in cases[k:] + cases[:k]:
            lab.security = level
            head = {"round": rnd, "kind": kind, "system": system, "security": level}
            try:
                rec = (
                    bench.latency(64, system)
                    if kind == "latency"
                    else bench.throughput(MIB, system)
                )
            except (CaseError, ValueError, OSError) as exc:
                rec = {"error": str(exc)}
            figure = rec.get("p50_us") if kind == "latency" else rec.get("mb_per_s")
            print(f"  {kind} {system} {level}: {figure}", file=sys.stderr, flush=True)
            runs.append({**head, **rec})
    return runs


def median(runs: list[Record], kind: str, system: str, level: str, key: str) -> float | None:
    values = [
        r[key]
        for r in runs
        if (r["kind"], r["system"], r["security"]) == (kind, system, level)
        and r.get(key) is not None
    ]
    return statistics.median(values) if values else None


def table(runs: list[Record]) -> tuple[list[str], list[Record]]:
    lines = [
        "| transport | security | 64 B p50 µs | × none | 1 MiB MB/s | × none | lost |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    goals: list[Record] = []
    for system in SYSTEMS:
        base_lat = median(runs, "latency", system, "none", "p50_us")
        base_thr = median(runs, "throughput", system, "none", "mb_per_s")
        for level in LEVELS:
            lat = median(runs, "latency", system, level, "p50_us")
            thr = median(runs, "throughput", system, level, "mb_per_s")
            lost = median(runs, "throughput", system, level, "lost")
            lat_x = lat / base_lat if lat and base_lat else None
            thr_x = thr / base_thr if thr and base_thr else None
            lines.append(
                f"| {system[3:]} | {level} | {fmt(lat)} | {fmt(lat_x, 2)} | "
                f"{fmt(thr)} | {fmt(thr_x, 2)} | {fmt(lost, 0)} |"
            )
            if level in LAT_GOAL:
                goals.append(
                    {
                        "system": system,
                        "security": level,
                        "what": "64 B p50 x none",
                        "value": lat_x,
                        "goal": f"<= {LAT_GOAL[level]}",
                        "pass": lat_x is not None and lat_x <= LAT_GOAL[level],
                    }
                )
            if level in THR_GOAL:
                goals.append(
                    {
                        "system": system,
                        "security": level,
                        "what": "1 MiB MB/s x none",
                        "value": thr_x,
                        "goal": f">= {THR_GOAL[level]}",
                        "pass": thr_x is not None and thr_x >= THR_GOAL[level],
                    }
                )
    return lines, goals


def fmt(value: float | None, digits: int = 1) -> str:
    return "-" if value is None else f"{value:,.{digits}f}"


def main() -> int:
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split()))
    parser.add_argument(
        "--quick",
        action="store_true",
        help=f"{QUICK_ROUNDS} rounds of a tenth of the samples: a smoke run",
    )
    parser.add_argument("--rounds", type=int)
    parser.add_argument("--build-dir", type=Path, default=REPO / "build" / "release")
    parser.add_argument(
        "--out", type=Path, default=REPO / "bench" / "results" / "network_security.json"
    )
    args = parser.parse_args()
    rounds = args.rounds or (QUICK_ROUNDS if args.quick else ROUNDS)
    bin_dir = args.build_dir / "bench" / "network"
    if not (bin_dir / "ln_pingpong").exists():
        print(
            f"bench_security: {bin_dir / 'ln_pingpong'} missing: run scons -j2 first",
            file=sys.stderr,
        )
        return 2
    if why := netlab_available():
        print(f"bench_security: network namespaces unavailable: {why}", file=sys.stderr)
        return 2
    load_start = os.getloadavg()
    started = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    with (
        tempfile.TemporaryDirectory(prefix="ln_bench_security_") as tmp,
        NetLab(Path(tmp)) as netlab,
    ):
        lab = Lab(netlab, bin_dir)
        bench = Bench(lab, args.quick)
        runs = measure(bench, lab, rounds)
    lines, goals = table(runs)
    head = (
        f"goals (issue 33): 64 B one-way p50 with authenticate <= 1.1x and with encrypt "
        f"<= 1.2x that of none; 1 MiB MB/s with encrypt >= 0.8x that of none; baseline "
        f"`none` measured in the same run, rounds alternate.  {rounds} rounds, "
        f"{bench.lat[64][0]} round trips per latency case, {bench.thr[MIB]} samples per "
        f"throughput case; network namespaces on one bridge, {os.cpu_count()} CPUs shared; "
        f"load average {load_start[0]:.2f} at start, {os.getloadavg()[0]:.2f} at end"
        + ("; --quick: a smoke run" if args.quick else "")
    )
    goal_lines = [
        "",
        "| transport | security | figure | value | goal | |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    goal_lines += [
        f"| {g['system'][3:]} | {g['security']} | {g['what']} | "
        f"{fmt(g['value'], 2)} | {g['goal']} | {'PASS' if g['pass'] else 'MISS'} |"
        for g in goals
    ]
    text = "\n".join([head, "", *lines, *goal_lines])
    print(text)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.with_suffix(".md").write_text(text + "\n")
    args.out.write_text(
        json.dumps(
            {
                "started": started,
                "quick": args.quick,
                "rounds": rounds,
                "cpu_count": os.cpu_count(),
                "kernel": platform.release(),
                "loadavg_start": load_start,
                "loadavg_end": os.getloadavg(),
                "runs": runs,
                "goals": goals,
            },
            indent=2,
        )
        + "\n"
    )
    print(f"\nwrote {args.out} and {args.out.with_suffix('.md')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
