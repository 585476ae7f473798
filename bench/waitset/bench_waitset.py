"""Benchmark of the waitset (docs/waiting.md, issue 29): wake-up latency of a 64 B sample
published every millisecond through a waitset against a blocking ln_read, in C and Python
(asyncio's `await sub.read_async()` against `sub.read()`); wake latency and CPU time per wait
with 1, 10, 100 and 1000 attached inports; and the CPU share of a process idling on 100
inports and a 1 s timer against one that only sleeps.  Runs build/release/bench/waitset/
waitset_bench and py_waitset.py with its own ln_manager (builds nothing: run scons first),
prints tables and the goals with PASS/MISS, writes bench/results/waitset.json and .txt,
exits 0 either way.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE.parent / "topics"))  # the process plumbing of bench/topics

import waitset_report as report  # noqa: E402
from topics_run import CaseError, Manager, Runner, can_pin, run_facts, warn_leftover  # noqa: E402

FULL = {"rounds": 3, "samples": 4000, "warmup": 200, "idle_s": 30.0}
QUICK = {"rounds": 1, "samples": 300, "warmup": 50, "idle_s": 5.0}
IDLE_INPORTS = 100
Record = dict[str, Any]
Cpus = tuple[int | None, int | None]  # (subscriber, publisher); None: the scheduler's choice


def log(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def python_async_missing() -> str | None:
    """None if `await sub.read_async()` is there, else what is missing."""
    try:
        import links_and_nodes as ln

        if not hasattr(ln.subscriber, "read_async"):
            return "ln.subscriber has no read_async (the Python asyncio API is not there yet)"
    except Exception as exc:  # noqa: BLE001 - any failure to load means "not available"
        return f"links_and_nodes does not load: {exc}"
    return None


def last_json(out: str, what: str) -> Record:
    lines = [line for line in out.splitlines() if line.startswith("{")]
    if not lines:
        raise CaseError(f"{what} printed no result: {out.strip()[-300:]!r}")
    return json.loads(lines[-1])


class Bench:
    """Runs one latency case (a subscriber, then the paced publisher) or the idle pair."""

    def __init__(self, args: argparse.Namespace, runner: Runner, cpus: Cpus) -> None:
        self.prog = str(args.build_dir / "bench" / "waitset" / "waitset_bench")
        self.samples, self.warmup = args.samples, args.warmup
        self.period_us = args.period_us
        self.runner, self.cpus = runner, cpus

    def subscriber(self, case: str, topic: str, out: Path) -> list[str]:
        tail = [str(self.samples), str(self.warmup), str(out)]
        if case.startswith("py_"):
            mode = "read" if case == "py_read" else "async"
            return [sys.executable, str(HERE / "py_waitset.py"), mode, topic, *tail]
        n = int(case.removeprefix("waitset")) if case.startswith("waitset") else 1
        mode = "waitset" if case.startswith("waitset") else case
        return [self.prog, "sub", mode, f"silent{n}", str(n), topic, *tail]

    def latency(self, case: str) -> tuple[Record, list[int]]:
        out = self.runner.path("lat")
        topic = f"wsbench{self.runner.serial}.{case}"
        pub = [self.prog, "pub", topic, str(self.samples + self.warmup), str(self.period_us)]
        sub_out, pub_out = self.runner.pair(self.subscriber(case, topic, out), pub, self.cpus, case)
        sent = last_json(pub_out, f"{case}: publisher")
        rec = {
            **last_json(sub_out, f"{case}: subscriber"),
            "late": sent["late"],
            "write_p50_us": sent["write_p50_ns"] / 1e3,
            "same_cpu": self.runner.same_cpu,
        }
        lat = report.read_latencies(out)
        rec["p50_us"] = report.percentile(sorted(lat), 0.5) / 1e3
        return rec, lat

    def idle(self, seconds: float) -> dict[str, Record]:
        """Both idle processes at once, on the same topics: the waitset one and the baseline
        that only sleeps."""
        procs = {
            kind: self.runner.spawn(
                [self.prog, "idle", kind, "idle", str(IDLE_INPORTS), str(seconds)], None
            )
            for kind in ("waitset", "sleep")
        }
        for kind, proc in procs.items():
            assert proc.stdout is not None
            if proc.stdout.readline().strip() != "ready":
                self.runner.kill_all()
                raise CaseError(f"idle {kind} did not start")
        return {
            kind: report.idle_stats(
                last_json(self.runner.finish(proc, f"idle {kind}"), f"idle {kind}")
            )
            for kind, proc in procs.items()
        }


def run_latency(
    bench: Bench, cases: list[str], rounds: int
) -> tuple[dict[str, list[Record]], dict[str, list[int]], dict[str, str]]:
    """Every round runs every case once, in an order that rotates from round to round, so
    drifting background load does not always hit the same one."""
    runs: dict[str, list[Record]] = {c: [] for c in cases}
    lat: dict[str, list[int]] = {c: [] for c in cases}
    errors: dict[str, str] = {}
    for rnd in range(rounds):
        order = cases[rnd % len(cases) :] + cases[: rnd % len(cases)]
        log(f"round {rnd + 1}/{rounds}")
        for case in order:
            try:
                rec, values = bench.latency(case)
            except (CaseError, ValueError, OSError) as exc:
                log(f"  {case}: ERROR {exc}")
                errors[case] = str(exc)
                continue
            runs[case].append({"round": rnd, **rec})
            lat[case] += values
            log(
                f"  {case}: p50 {rec['p50_us']:.1f} µs, "
                f"CPU {rec['cpu_s'] / max(rec['waits'], 1) * 1e6:.2f} µs/wait"
            )
    return runs, lat, errors


def placement(args: argparse.Namespace) -> tuple[Cpus, str]:
    usable = sorted(os.sched_getaffinity(0))
    if args.no_pin or len(usable) < 2:
        return (None, None), (
            "the scheduler's placement"
            if args.no_pin
            else f"the scheduler's placement (only {len(usable)} usable CPU)"
        )
    sub_cpu, pub_cpu = usable[-1], usable[0]
    why_not = can_pin([sub_cpu, pub_cpu])
    if why_not:
        return (None, None), f"the scheduler's placement (pinning unavailable: {why_not})"
    return (sub_cpu, pub_cpu), f"subscriber on CPU {sub_cpu}, publisher on CPU {pub_cpu}"


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split()))
    parser.add_argument(
        "--quick",
        action="store_true",
        help=f"{QUICK['rounds']} round of {QUICK['samples']} samples per case, "
        f"{QUICK['idle_s']:.0f} s idle: a smoke run, not a measurement",
    )
    parser.add_argument("--rounds", type=int, help=f"rounds (default {FULL['rounds']})")
    parser.add_argument(
        "--samples", type=int, help=f"timed samples per case and round (default {FULL['samples']})"
    )
    parser.add_argument(
        "--warmup", type=int, help=f"samples before them (default {FULL['warmup']})"
    )
    parser.add_argument(
        "--period-us", type=int, default=1000, help="the publisher's pace in µs (default 1000)"
    )
    parser.add_argument(
        "--idle-seconds",
        type=float,
        help=f"length of the idle measurement (default {FULL['idle_s']:.0f})",
    )
    parser.add_argument(
        "--no-pin",
        action="store_true",
        help="leave both processes to the scheduler (default: the subscriber "
        "on the last usable CPU, the publisher on the first)",
    )
    parser.add_argument(
        "--build-dir",
        type=Path,
        default=REPO / "build" / "release",
        help="SCons variant directory with bench/waitset/ (build/release)",
    )
    parser.add_argument(
        "--json",
        type=Path,
        default=REPO / "bench" / "results" / "waitset.json",
        help="where the results go (bench/results/waitset.json; the table beside it as .txt)",
    )
    args = parser.parse_args()
    size = QUICK if args.quick else FULL
    args.rounds = args.rounds or size["rounds"]
    args.samples = args.samples or size["samples"]
    args.warmup = size["warmup"] if args.warmup is None else args.warmup
    args.idle_seconds = args.idle_seconds or size["idle_s"]
    return args


def print_report(
    args: argparse.Namespace,
    facts: Record,
    summary: dict[str, Record],
    idle: dict[str, Record],
    goal_rows: list[Record],
    unavailable: dict[str, str],
) -> str:
    lines = [
        "goals (issue 29): waitset p50 <= 1.2x the blocking read's p50, in C and in Python "
        "(asyncio); wake p50 and CPU per wait at 1000 inports <= 1.2x at 1; a process idling "
        "on 100 inports and a 1 s timer < 0.1 % CPU",
        f"cpu: os.cpu_count()={os.cpu_count()}, usable={facts['usable_cpus']}; "
        f"{facts['placement']}; load average at start {facts['loadavg_start'][0]:.2f}, "
        f"at end {facts['loadavg_end'][0]:.2f}"
        + ("; --quick: a smoke run, the numbers are not a measurement" if args.quick else ""),
        "",
        f"wake-up latency, 64 B, one sample every {args.period_us} µs (the subscriber sleeps "
        f"before each), {args.rounds} round(s) of {args.samples:,} samples per case after "
        f"{args.warmup:,} warm-up: one way = CLOCK_MONOTONIC when the read returned minus the "
        "publisher's stamp written into the sample just before ln_write (a queued subscriber, "
        "16 buffers: a late read is timed, not skipped); CPU µs/wait = the subscriber's "
        "getrusage user+sys over the timed samples / its waits; write µs = the publisher's "
        "ln_write p50 (commit and wake-up call); both medians of the rounds",
        *report.latency_table(summary, unavailable),
        "",
        f"idle, {args.idle_seconds:.0f} s, both processes at once (CPU % = getrusage "
        "user+sys / wall)",
        *report.idle_table(idle, IDLE_INPORTS),
        "",
        *report.goals_table(goal_rows),
    ]
    text = "\n".join(lines)
    print(text)
    return text


def main() -> int:
    args = parse_args()
    prog = args.build_dir / "bench" / "waitset" / "waitset_bench"
    if not prog.exists():
        print(f"bench_waitset: {prog} is missing: build it first with `scons -j2`", file=sys.stderr)
        return 2
    unavailable: dict[str, str] = {}
    why = python_async_missing()
    if why:
        unavailable["py_async"] = why
    cases = [c for c in report.CASES if c not in unavailable]
    cpus, where = placement(args)
    facts = {
        **run_facts(time.strftime("%Y-%m-%dT%H:%M:%S%z"), args.quick),
        "usable_cpus": sorted(os.sched_getaffinity(0)),
        "placement": where,
        "loadavg_start": os.getloadavg(),
    }
    idle: dict[str, Record] = {}
    with tempfile.TemporaryDirectory(prefix="ln_bench_waitset_") as tmp_name:
        tmp = Path(tmp_name)
        manager = Manager.start(tmp)
        runner = Runner(tmp, manager.process.env)  # LN_MANAGER and LN_RUNTIME_DIR set
        bench = Bench(args, runner, cpus)
        try:
            runs, lat, errors = run_latency(bench, cases, args.rounds)
            log(f"idle, {args.idle_seconds:.0f} s")
            try:
                idle = bench.idle(args.idle_seconds)
            except (CaseError, ValueError, OSError) as exc:
                log(f"  idle: ERROR {exc}")
                errors["idle"] = str(exc)
        finally:
            runner.kill_all()
            leftover = manager.stop()
    facts["loadavg_end"] = os.getloadavg()
    summary = {c: report.case_stats(lat[c], runs[c]) for c in cases if runs[c]}
    unavailable.update({c: f"failed: {e}" for c, e in errors.items() if c not in summary})
    goal_rows = report.goals(summary, idle, unavailable)
    text = print_report(args, facts, summary, idle, goal_rows, unavailable)
    warn_leftover(leftover)

    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.with_suffix(".txt").write_text(text + "\n")
    args.json.write_text(
        json.dumps(
            {
                **facts,
                "rounds": args.rounds,
                "samples": args.samples,
                "warmup": args.warmup,
                "period_us": args.period_us,
                "idle_seconds": args.idle_seconds,
                "idle_inports": IDLE_INPORTS,
                "unavailable": unavailable,
                "errors": errors,
                "runs": runs,
                "summary": summary,
                "idle": idle,
                "goals": goal_rows,
                "leftover_segments": leftover,
            },
            indent=2,
        )
        + "\n"
    )
    print(f"\nwrote {args.json} and {args.json.with_suffix('.txt').name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
