"""ln_log benchmark: what one log line costs a 1 kHz C control loop (docs/logging.md,
"Client logging").

Goal (issue: "ln_log from a 1 kHz C loop costs < 1 us per call (no system call on the fast
path) and never blocks"), each measured in the same run against a baseline:
  (a) cost: the median time of one ln_log of a formatted line in a 1 kHz loop, minus the
      median of the same loop timing nothing (the baseline: two clock_gettime calls);
      goal: < 1,000 ns.
  (b) system calls: strace of the loop's own thread (not the client's sender thread), from
      the getppid() before the loop to the one after it, with ln_log and without; the calls
      ln_log adds per period are (log - baseline) / N; goal: 0 (both loops make exactly one
      clock_nanosleep per period).

bench_ln_log (bench/logging/bench_ln_log.c) is built by scons into build/release/bench/
logging/ (this script builds nothing); a private ln_manager collects the lines.  Prints a
table, writes bench/results/ln_log.json and ln_log.md, exits 0 whether the goals are met or
not.  --quick: 500 periods instead of 5,000.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import uuid
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(REPO / "python"))  # measure this checkout, not an installed one

from links_and_nodes.manager.frontends.launch import start_manager  # noqa: E402

PROGRAM = REPO / "build" / "release" / "bench" / "logging" / "bench_ln_log"
RESULTS = REPO / "bench" / "results"
GOAL_NS = 1000
LIMIT = 300.0  # seconds: only an upper bound against a hang


def run(env: dict[str, str], mode: str, n: int) -> dict[str, Any]:
    done = subprocess.run([str(PROGRAM), mode, str(n)], capture_output=True, text=True,
                          env=env, timeout=LIMIT, check=True)
    return dict(json.loads(done.stdout.splitlines()[-1]))


def syscalls(env: dict[str, str], mode: str, n: int, tmp: Path) -> dict[str, int]:
    """System calls of the program's main thread between its two getppid() markers, by name
    (strace without -f follows no other thread)."""
    out = tmp / f"strace_{mode}_{n}.txt"
    subprocess.run(["strace", "-o", str(out), str(PROGRAM), mode, str(n)],
                   capture_output=True, text=True, env=env, timeout=LIMIT, check=True)
    names = [line.split("(", 1)[0] for line in out.read_text().splitlines()
             if "(" in line and not line.startswith(("+++", "---"))]
    marks = [i for i, name in enumerate(names) if name == "getppid"]
    if len(marks) != 2:
        raise RuntimeError(f"{out}: {len(marks)} getppid markers, expected 2")
    counts: dict[str, int] = {}
    for name in names[marks[0] + 1:marks[1]]:
        counts[name] = counts.get(name, 0) + 1
    return counts


def _names(counts: dict[str, int]) -> str:
    return ", ".join(f"{name} {count}" for name, count in sorted(counts.items())) or "none"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="500 periods instead of 5,000")
    args = ap.parse_args()
    if not PROGRAM.exists():
        print(f"{PROGRAM} is missing: run scons first", file=sys.stderr)
        return 2
    n = 500 if args.quick else 5000
    with tempfile.TemporaryDirectory() as tmp_dir:
        tmp = Path(tmp_dir)
        manager = start_manager(f"benchlnlog{os.getpid()}x{uuid.uuid4().hex[:6]}",
                                tmp / "runtime", tmp / "manager.log", "--log-level", "warning")
        try:
            env = manager.env
            base, logged = run(env, "base", n), run(env, "log", n)
            counts: dict[str, dict[str, int]] = {}
            if shutil.which("strace"):
                for mode in ("base", "log"):
                    counts[mode] = syscalls(env, mode, n, tmp)
        finally:
            manager.stop()
    cost = logged["median_ns"] - base["median_ns"]
    per_call = None
    if counts:
        per_call = (sum(counts["log"].values()) - sum(counts["base"].values())) / n
    result = {
        "goal": "ln_log from a 1 kHz C loop: < 1 us per call, no system call on the fast path",
        "host": platform.node(), "machine": platform.machine(), "periods": n,
        "quick": args.quick, "baseline": base, "ln_log": logged,
        "cost_median_ns": cost, "goal_ns": GOAL_NS, "cost_met": cost < GOAL_NS,
        "syscalls_main_thread": counts, "syscalls_per_call": per_call,
        "syscalls_met": per_call == 0 if per_call is not None else None,
    }
    table = [
        "| loop (1 kHz, C) | median ns | p99 ns | max ns | lines queued | dropped |",
        "| --- | ---: | ---: | ---: | ---: | ---: |",
        f"| baseline (timing only) | {base['median_ns']} | {base['p99_ns']} | "
        f"{base['max_ns']} | - | - |",
        f"| ln_log per period | {logged['median_ns']} | {logged['p99_ns']} | "
        f"{logged['max_ns']} | {logged['queued']} | {logged['dropped']} |",
        "",
        f"ln_log cost (median minus baseline): {cost} ns (goal < {GOAL_NS} ns: "
        f"{'met' if cost < GOAL_NS else 'NOT met'})",
    ]
    if counts:
        table += [
            "",
            f"| system calls of the loop's thread in {n} periods (strace) | calls |",
            "| --- | --- |",
            f"| baseline | {_names(counts['base'])} |",
            f"| with ln_log | {_names(counts['log'])} |",
            "",
            f"system calls ln_log adds per call: {per_call:g} (goal 0: "
            f"{'met' if per_call == 0 else 'NOT met'})",
        ]
    print("\n".join(table))
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "ln_log.json").write_text(json.dumps(result, indent=2) + "\n")
    (RESULTS / "ln_log.md").write_text("# ln_log in a 1 kHz loop (bench/logging/bench_ln_log.py"
                                       f"{' --quick' if args.quick else ''})\n\n"
                                       + "\n".join(table) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
