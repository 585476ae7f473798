"""Benchmark of service calls between hosts by `security` level (docs/security.md, "Remote
service calls"): the round trip of a 64-byte request and response over TCP (the caller gets
another host id than the provider) with none, authenticate and encrypt, in the same run and
in alternating rounds, one ln_manager per level.  Goal: authenticate <= 1.1x and encrypt
<= 1.2x the median round trip of none.  Uses bench/services/svc_ln (run scons first).
Prints a table, writes bench/results/service_security.json and .md; exits 0 either way.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
import uuid
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(REPO / "tests" / "python"))  # buildtree: where scons put svc_ln

from buildtree import build_dir  # noqa: E402

from links_and_nodes.manager.frontends import launch  # noqa: E402

LEVELS = ("none", "authenticate", "encrypt")
GOALS = {"authenticate": 1.1, "encrypt": 1.2}  # most median round trip, times none's
COUNT, WARMUP, ROUNDS = 20000, 2000, 5
QUICK_COUNT, QUICK_WARMUP, QUICK_ROUNDS = 2000, 200, 3
LIMIT = 120.0  # seconds any one process may take, never a measurement


def one_round(svc_ln: Path, env: dict[str, str], count: int, warmup: int,
              out: Path) -> list[int]:
    """Round trips (ns) of `count` calls after `warmup` through one provider over TCP."""
    name = f"bench.sec{uuid.uuid4().hex[:8]}"
    provider = subprocess.Popen([str(svc_ln), "provide", name, str(count + warmup)], env=env,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert provider.stdout is not None
        if provider.stdout.readline().strip() != "ready":
            raise RuntimeError("svc_ln provide did not get ready")
        caller = subprocess.run([str(svc_ln), "call", name, str(count), str(warmup), str(out)],
                                env={**env, "LN_HOST_ID": "bench-other-host"},
                                capture_output=True, text=True, timeout=LIMIT)
        if caller.returncode != 0:
            raise RuntimeError(f"svc_ln call failed: {caller.stderr.strip()}")
        provider.wait(timeout=LIMIT)
    finally:
        if provider.poll() is None:
            provider.kill()
            provider.wait()
    raw = out.read_bytes()
    return [int.from_bytes(raw[i:i + 8], "little") for i in range(0, len(raw), 8)]


def stats(samples: list[int]) -> dict[str, float]:
    ordered = sorted(samples)
    return {"median_us": statistics.median(ordered) / 1e3,
            "p99_us": ordered[min(len(ordered) - 1, int(len(ordered) * 0.99))] / 1e3,
            "calls": len(ordered)}


def table(levels: dict[str, dict[str, Any]]) -> str:
    base = levels["none"]["median_us"]
    lines = ["| security | median µs | p99 µs | × none | goal | verdict |",
             "|---|---:|---:|---:|---:|---|"]
    for level, r in levels.items():
        goal = GOALS.get(level)
        ratio = r["median_us"] / base
        verdict = "" if goal is None else ("PASS" if ratio <= goal else "MISS")
        lines.append(f"| {level} | {r['median_us']:.1f} | {r['p99_us']:.1f} | {ratio:.3f} | "
                     f"{'' if goal is None else f'≤ {goal}'} | {verdict} |")
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help=f"{QUICK_COUNT} calls x {QUICK_ROUNDS} rounds per level")
    parser.add_argument("--out", type=Path, default=REPO / "bench" / "results",
                        help="directory of service_security.json/.md")
    args = parser.parse_args()
    count, warmup, rounds = ((QUICK_COUNT, QUICK_WARMUP, QUICK_ROUNDS) if args.quick
                             else (COUNT, WARMUP, ROUNDS))
    svc_ln = build_dir() / "bench" / "services" / "svc_ln"
    if not svc_ln.exists():
        print(f"{svc_ln} is missing: run scons first", file=sys.stderr)
        return 0
    samples: dict[str, list[int]] = {level: [] for level in LEVELS}
    with tempfile.TemporaryDirectory(prefix="ln-bench-sec-") as tmp:
        managers = {level: launch.start_manager(f"bsec-{level[:4]}-{uuid.uuid4().hex[:8]}",
                                                Path(tmp) / level, Path(tmp) / f"{level}.log",
                                                "--service-security", level)
                    for level in LEVELS}
        try:
            for r in range(rounds):  # alternate the order so drift hits every level alike
                order = LEVELS if r % 2 == 0 else tuple(reversed(LEVELS))
                for level in order:
                    samples[level] += one_round(svc_ln, managers[level].env, count, warmup,
                                                Path(tmp) / "rtt")
                    print(f"round {r + 1}/{rounds} {level}: done", file=sys.stderr)
        finally:
            for m in managers.values():
                m.stop()
    levels = {level: stats(s) for level, s in samples.items()}
    base = levels["none"]["median_us"]
    result = {
        "bench": "service_security",
        "goal": "authenticate <= 1.1x and encrypt <= 1.2x of none (median 64 B round trip, "
                "TCP between two processes on one machine)",
        "quick": args.quick, "rounds": rounds, "calls_per_round": count, "warmup": warmup,
        "when": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "machine": {"cpus": os.cpu_count(), "platform": platform.platform()},
        "levels": {level: {**r, "ratio_to_none": r["median_us"] / base,
                           "goal": GOALS.get(level),
                           "pass": None if level not in GOALS
                           else r["median_us"] / base <= GOALS[level]}
                   for level, r in levels.items()},
    }
    text = table(levels)
    print(text)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "service_security.json").write_text(json.dumps(result, indent=2) + "\n")
    (args.out / "service_security.md").write_text(
        "# Service calls between hosts by security level\n\n"
        f"{result['goal']}; {'quick' if args.quick else 'full'} run, {rounds} rounds of "
        f"{count} calls per level, {result['when']}, {os.cpu_count()} CPUs (shared).\n\n"
        f"{text}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
