"""Benchmark of parameter blocks (docs/parameters.md): the cost of update() in a control loop
when nothing changed, against the floor of copying the same inputs to the outputs; whether
update() makes any system call; and the latency from a set (a call of the block's service)
to the value visible in the loop, for a spinning loop and a 1 kHz loop.  Runs
build/release/bench/parameters/param_bench against its own ln_manager (builds nothing: run
scons first), prints a table with the goal and PASS/MISS, writes
bench/results/parameters.json, exits 0 either way.
"""

from __future__ import annotations

import argparse
import json
import os
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
sys.path.insert(0, str(REPO / "python"))
sys.path.insert(0, str(REPO))

from links_and_nodes.manager.frontends.launch import start_manager  # noqa: E402

GOAL_NS = 50.0  # update() with no pending change
FULL = {"calls": 10_000_000, "rounds": 7, "sets": 1000}
QUICK = {"calls": 1_000_000, "rounds": 3, "sets": 200}


def us(ns: float) -> str:
    return f"{ns / 1000:.1f}"


def main() -> int:
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split()))
    parser.add_argument("--quick", action="store_true",
                        help="fewer calls, rounds and sets: a smoke run, not a measurement")
    parser.add_argument("--build-dir", type=Path, default=REPO / "build" / "release",
                        help="SCons variant directory with bench/parameters/ (build/release)")
    parser.add_argument("--json", type=Path,
                        default=REPO / "bench" / "results" / "parameters.json",
                        help="where the results go (bench/results/parameters.json)")
    args = parser.parse_args()
    program = args.build_dir / "bench" / "parameters" / "param_bench"
    if not program.exists():
        print(f"bench_parameters: {program} is missing: build it first with `scons -j2`",
              file=sys.stderr)
        return 2
    size = QUICK if args.quick else FULL
    started = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    load_start = os.getloadavg()
    with tempfile.TemporaryDirectory(prefix="ln_bench_parameters_") as tmp_name:
        tmp = Path(tmp_name)
        mgr = start_manager(f"pbench{os.getpid()}x{uuid.uuid4().hex[:8]}", tmp / "run",
                            tmp / "manager.log")
        try:
            done = subprocess.run([str(program), str(size["calls"]), str(size["rounds"]),
                                   str(size["sets"])], capture_output=True, text=True,
                                  env=mgr.env, timeout=600)
        finally:
            mgr.stop()
    if done.returncode != 0:
        print(f"bench_parameters: param_bench failed ({done.returncode}): {done.stderr}",
              file=sys.stderr)
        return 0
    result: dict[str, Any] = json.loads(done.stdout)
    update = statistics.median(result["update_ns"])
    floor = statistics.median(result["floor_ns"])
    goal_met = update <= GOAL_NS and result["syscalls"] == "none"

    print(f"goal: update() with no pending change <= {GOAL_NS:.0f} ns and no system call")
    print(f"cpu: os.cpu_count()={os.cpu_count()}, usable={len(os.sched_getaffinity(0))}; "
          f"load average at start {load_start[0]:.2f}, at end {os.getloadavg()[0]:.2f}"
          + ("; --quick: a smoke run, the numbers are not a measurement" if args.quick
             else ""))
    print()
    print(f"update() of a block with 6 parameters ({result['copied_bytes']} bytes of inputs "
          f"copied to outputs), ns per call: median (min) over {size['rounds']} rounds of "
          f"{size['calls']:,} calls")
    rows = [("ln_parameter_block_update, nothing pending",
             f"{update:.1f} ({min(result['update_ns']):.1f})"),
            ("floor: the same 5 memcpy of the inputs",
             f"{floor:.1f} ({min(result['floor_ns']):.1f})"),
            ("update() minus the floor", f"{update - floor:.1f}"),
            ("system calls in update() (seccomp, "
             f"{result['syscall_check_updates']:,} calls incl. a change)", result["syscalls"])]
    width = max(len(r[0]) for r in rows)
    for name, value in rows:
        print(f"  {name.ljust(width)}  {value}")
    print()
    print("set -> visible in the loop, µs (a set of one double through the block's service "
          "from a thread of the same process; the sets are spaced)")
    print(f"  {'loop':<28} {'n':>5} {'p50':>8} {'p90':>8} {'p99':>8} {'max':>9}")
    for key, name in (("spin_visible_ns", "spinning loop: visible"),
                      ("spin_call_ns", "spinning loop: set call"),
                      ("khz_visible_ns", "1 kHz loop: visible"),
                      ("khz_call_ns", "1 kHz loop: set call")):
        s = result[key]
        print(f"  {name:<28} {s['n']:>5} {us(s['p50']):>8} {us(s['p90']):>8} "
              f"{us(s['p99']):>8} {us(s['max']):>9}")
    print()
    print(f"goal: {'PASS' if goal_met else 'MISS'} (update {update:.1f} ns, "
          f"system calls: {result['syscalls']})")

    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({
        "started": started, "quick": args.quick, "cpu_count": os.cpu_count(),
        "loadavg_start": load_start, "loadavg_end": os.getloadavg(), **size,
        "goal": {"update_ns_max": GOAL_NS, "syscalls": "none"},
        "update_ns_median": update, "floor_ns_median": floor, "goal_met": goal_met,
        "raw": result}, indent=2) + "\n")
    print(f"\nresults: {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
