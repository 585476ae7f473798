"""Benchmark of the Rust bindings' topics (issue 27, "Measure"): ping-pong one-way latency of
links_and_nodes' safe Rust API (lat_rust) beside libln's C (bench/topics/lat_ln) and the
iceoryx2 crate (lat_iox2), in one run with its own ln_manager, the scheduler's placement (os),
both processes on one CPU (pinned) and, as context, on one CPU each (split), median of
repetitions.  Goals: Rust p50 <= 1.1x C at 64 B, 4 KiB and 1 MiB, copy and zero-copy; Rust
zero-copy of the whole sample ahead of iceoryx2 at 64 B and 4 MiB.  Builds the Rust programs
(cargo, build/cargo-bench), not lat_ln (run scons -j2 first).  Prints the tables and
PASS/MISS, writes bench/results/rust.json and rust.txt, exits 0 either way."""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE.parent / "topics"))  # the process plumbing of bench/topics

import rust_report as report  # noqa: E402
from topics_report import one_way_stats  # noqa: E402
from topics_run import CaseError, Manager, Runner, can_pin, run_facts, warn_leftover  # noqa: E402

MIB = 1 << 20
SIZES = [64, 4096, MIB, 4 * MIB]
MODES = ["copy", "zc", "full"]
# size -> (round trips, warm-up) of one repetition; --quick: QUICK_ITERATIONS, 1 repetition
ITERATIONS = {64: (20000, 2000), 4096: (20000, 2000), MIB: (2000, 200), 4 * MIB: (1000, 100)}
QUICK_ITERATIONS = {64: (3000, 300), 4096: (3000, 300), MIB: (300, 30), 4 * MIB: (150, 15)}
REPS = 7
Record = dict[str, Any]
Cpus = tuple[int | None, int | None]  # (pong, ping); None: the scheduler's choice


def log(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def cargo() -> str | None:
    home = Path(os.environ.get("CARGO_HOME", Path.home() / ".cargo"))
    return shutil.which("cargo") or shutil.which("cargo", path=str(home / "bin"))


def build(target_dir: Path) -> str | None:
    """cargo build --release of lat_rust and lat_iox2; None, or why it failed."""
    exe = cargo()
    if exe is None:
        return "cargo not found"
    argv = [
        exe,
        "build",
        "--release",
        "--locked",
        "-j",
        "2",
        "--manifest-path",
        str(HERE / "Cargo.toml"),
        "--target-dir",
        str(target_dir),
    ]
    log(" ".join(argv))
    env = {**os.environ, "PATH": f"{Path(exe).parent}{os.pathsep}{os.environ['PATH']}"}
    done = subprocess.run(argv, env=env, capture_output=True, text=True)
    return None if done.returncode == 0 else done.stderr.strip()[-2000:]


def locked_version(crate: str) -> str | None:
    """The version of `crate` in bench/rust/Cargo.lock."""
    text = (HERE / "Cargo.lock").read_text()
    found = re.search(rf'name = "{re.escape(crate)}"\nversion = "([^"]+)"', text)
    return found.group(1) if found else None


def tool_version(argv: list[str]) -> str | None:
    try:
        return subprocess.run(argv, capture_output=True, text=True).stdout.strip() or None
    except OSError:
        return None


class Bench:
    """Runs one case: a pong, then a ping that times the round trips."""

    def __init__(self, programs: dict[str, Path], runner: Runner, quick: bool) -> None:
        self.programs = programs
        self.runner = runner
        self.iterations = QUICK_ITERATIONS if quick else ITERATIONS

    def case(self, transport: str, size: int, mode: str, cpus: Cpus) -> Record:
        count, warmup = self.iterations[size]
        out = self.runner.path("rtt")
        name = f"bench.rs{self.runner.serial}"
        prog = str(self.programs[transport])
        pong = [prog, "pong", name, str(size), mode, str(count + warmup), str(warmup)]
        ping = [prog, "ping", name, str(size), mode, str(count), str(warmup), str(out)]
        pong_out, ping_out = self.runner.pair(pong, ping, cpus, f"{transport} {mode}")
        faults = {
            "ping_minflt": last_json(ping_out)["minflt"],
            "pong_minflt": last_json(pong_out)["minflt"],
        }
        per_sample = {f"{k}_per_sample": v / count for k, v in faults.items()}
        return {
            **one_way_stats(out),
            "warmup": warmup,
            "same_cpu": self.runner.same_cpu,
            **faults,
            **per_sample,
        }


def last_json(out: str) -> Record:
    result: Record = json.loads(out.strip().splitlines()[-1])
    return result


def placements(usable: list[int], pin_cpu: int) -> tuple[dict[str, Cpus], str]:
    """os: the scheduler's placement; pinned: both on pin_cpu; split (context, not judged):
    pong on another CPU, ping on pin_cpu (where the process may pin)."""
    where: dict[str, Cpus] = {"os": (None, None)}
    other = [c for c in usable if c != pin_cpu]
    why_not = can_pin([pin_cpu, *other[:1]])
    if why_not:
        return where, f"pinning unavailable: {why_not}"
    where["pinned"] = (pin_cpu, pin_cpu)
    if other:
        where["split"] = (other[0], pin_cpu)
    return where, "available (sched_setaffinity)"


def placement_text(cpus: Cpus) -> str:
    if cpus[0] is None:
        return "the scheduler's"
    if cpus[0] == cpus[1]:
        return f"both on CPU {cpus[0]}"
    return f"pong on CPU {cpus[0]}, ping on CPU {cpus[1]} (context: not judged)"


def run_all(bench: Bench, where: dict[str, Cpus], reps: int) -> list[Record]:
    """Every repetition runs every case; the transports of one size and mode run back to
    back, their order rotated from repetition to repetition."""
    records: list[Record] = []
    transports = list(report.TRANSPORTS)
    for rep in range(reps):
        order = transports[rep % 3 :] + transports[: rep % 3]
        for placement, cpus in where.items():
            log(f"repetition {rep + 1}/{reps}, {placement}")
            for size in SIZES:
                for mode in MODES:
                    for transport in order:
                        records.append(
                            {
                                "rep": rep,
                                "placement": placement,
                                "size": size,
                                "mode": mode,
                                "transport": transport,
                                **attempt(bench, transport, size, mode, cpus),
                            }
                        )
    return records


def attempt(bench: Bench, transport: str, size: int, mode: str, cpus: Cpus) -> Record:
    t0 = time.monotonic()
    what = f"  {report.size_label(size)} {mode} {transport}"
    try:
        rec = bench.case(transport, size, mode, cpus)
    except (CaseError, ValueError, KeyError, IndexError, OSError) as exc:
        log(f"{what}: ERROR {exc}")
        return {"error": str(exc)}
    log(f"{what}: p50 {rec['p50_us']:.2f} µs ({time.monotonic() - t0:.1f} s)")
    return rec


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split()))
    parser.add_argument(
        "--quick",
        action="store_true",
        help="a few thousand round trips (fewer for MiB sizes), 1 repetition",
    )
    parser.add_argument("--reps", type=int, help=f"repetitions (default {REPS}; --quick: 1)")
    parser.add_argument("--cpu", type=int, help="CPU for the pinned runs (default: the last)")
    parser.add_argument(
        "--build-dir",
        type=Path,
        default=REPO / "build" / "release",
        help="SCons variant directory with bench/topics/lat_ln",
    )
    parser.add_argument(
        "--target-dir",
        type=Path,
        default=REPO / "build" / "cargo-bench",
        help="cargo target directory of bench/rust",
    )
    parser.add_argument("--no-build", action="store_true", help="do not run cargo build")
    parser.add_argument(
        "--json",
        type=Path,
        default=REPO / "bench" / "results" / "rust.json",
        help="where the results go (the table beside it, .txt)",
    )
    args = parser.parse_args()
    if args.reps is None:
        args.reps = 1 if args.quick else REPS
    return args


def header(facts: Record, where: dict[str, Cpus], reps: int) -> list[str]:
    quick = "; --quick: a smoke run, not a measurement" if facts["quick"] else ""
    return [
        "goals: Rust p50 <= 1.1x C (lat_ln) at 64 B, 4 KiB, 1 MiB, copy and zero-copy (zc);",
        "       Rust zero-copy of the whole sample (full) p50 ahead of iceoryx2 at 64 B, 4 MiB",
        f"measured: {facts['commit']}; {facts['rustc']}; iceoryx2 {facts['iceoryx2']} (crate); "
        f"median of {reps} repetition(s){quick}",
        f"cpu: usable {facts['usable_cpus']}; pinning: {facts['pinning']}; load average at "
        f"start {facts['loadavg_start'][0]:.2f}, at end {facts['loadavg_end'][0]:.2f}",
        "one-way latency = round trip / 2 in µs; modes: copy (write/read of the whole sample), "
        "zc (loan/borrow, first and last 8 bytes, as lat_ln zc), full (loan/borrow, the whole "
        "sample copied in and out); iceoryx2 waits by polling receive() with sched_yield",
        "placements (pong CPU, ping CPU): "
        + ", ".join(f"{p} {c}" for p, c in where.items())
        + "; same C/R/I: median share (%) of the time both sides had last run on one CPU, "
        "for ln C, ln Rust and iceoryx2",
    ]


def main() -> int:
    args = parse_args()
    programs = {
        "ln_c": args.build_dir / "bench" / "topics" / "lat_ln",
        "ln_rust": args.target_dir / "release" / "lat_rust",
        "iox2": args.target_dir / "release" / "lat_iox2",
    }
    if not args.no_build and (why := build(args.target_dir)):
        print(f"bench_rust: cargo build failed:\n{why}", file=sys.stderr)
        return 2
    missing = [str(p) for p in programs.values() if not p.exists()]
    if missing:
        print(f"bench_rust: missing {', '.join(missing)} (lat_ln: `scons -j2`)", file=sys.stderr)
        return 2
    usable = sorted(os.sched_getaffinity(0))
    pin_cpu = args.cpu if args.cpu is not None else usable[-1]
    where, pin_text = placements(usable, pin_cpu)
    facts: Record = {
        **run_facts(time.strftime("%Y-%m-%dT%H:%M:%S%z"), args.quick),
        "usable_cpus": usable,
        "pinning": pin_text,
        "loadavg_start": os.getloadavg(),
        "reps": args.reps,
        "iterations": QUICK_ITERATIONS if args.quick else ITERATIONS,
        "commit": tool_version(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"]),
        "rustc": tool_version(["rustc", "--version"]),
        "iceoryx2": locked_version("iceoryx2"),
        "programs": {k: str(v) for k, v in programs.items()},
    }
    with tempfile.TemporaryDirectory(prefix="ln_bench_rust_") as tmp_name:
        tmp = Path(tmp_name)
        manager = Manager.start(tmp)
        runner = Runner(tmp, manager.process.env)  # LN_MANAGER and LN_RUNTIME_DIR set
        try:
            records = run_all(Bench(programs, runner, args.quick), where, args.reps)
        finally:
            runner.kill_all()
            leftover = manager.stop()
    facts["loadavg_end"] = os.getloadavg()
    med = report.medians(records)
    judged = [p for p in report.JUDGED if p in where]
    goals = report.goals(med, judged)
    lines = header(facts, where, args.reps)
    for placement, cpus in where.items():
        what = placement_text(cpus)
        lines += ["", *report.latency_table(med, placement, what, SIZES, MODES)]
    lines += ["", *report.goals_table(goals, judged)]
    print("\n".join(lines))
    warn_leftover(leftover)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.with_suffix(".txt").write_text("\n".join(lines) + "\n")
    args.json.write_text(
        json.dumps(
            {
                **facts,
                "placements": where,
                "leftover_segments": leftover,
                "goals": goals,
                "medians": [
                    {"placement": k[0], "size": k[1], "mode": k[2], "transport": k[3], **v}
                    for k, v in med.items()
                ],
                "runs": records,
            },
            indent=2,
        )
        + "\n"
    )
    print(f"\nwrote {args.json} and {args.json.with_suffix('.txt').name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
