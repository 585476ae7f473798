"""Benchmark of real-time tails: a 10 kHz 64 B ping-pong and the demo robot's 1 kHz control
pair (joint_state out, command back), each with links_and_nodes, iceoryx and a raw futex floor
in the same run, under SCHED_FIFO, mlockall and CPU pinning as a `.lnc` sets them (policy,
priority, affinity), while stress-ng loads CPU, memory and I/O and a manager with its web UI,
an ln_daemon keeping a topic logger, ln_record and a WebSocket scope run.  Prints the table
and the goal with PASS/MISS, writes bench/results/realtime.json and realtime.txt, exits 0
either way (builds nothing: run scons first)."""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import rt_report as report
from rt_load import PREFIX, STRESS, Background

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE.parent / "topics"))
from topics_peers import Iceoryx  # noqa: E402
from topics_run import CaseError, Runner, can_pin, run_facts  # noqa: E402

SHAPES = {"pingpong": 10_000.0, "control": 1_000.0}  # shape -> loop rate (Hz)
FULL_PINGPONG = 1_000_000  # samples per transport: 100 s at 10 kHz
QUICK_SECONDS = 3.0  # per case with --quick
SPIN_US = 20  # iceoryx waits like libln's default spin_us
Record = dict[str, Any]


def log(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def fifo_allowed(priority: int) -> str | None:
    """None if this process may use SCHED_FIFO at `priority` (tried and undone), else why."""
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except OSError as exc:
        return f"sched_setscheduler(SCHED_FIFO, {priority}) failed: {exc.strerror}"
    os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
    return None


class RtRunner(Runner):
    """Runner whose children get policy, priority and affinity between fork and exec, in
    the order ln_daemon applies a process's `.lnc` keys (ln_daemon/os_linux.cpp)."""

    def __init__(self, tmp: Path, env: dict[str, str], priority: int | None) -> None:
        super().__init__(tmp, env)
        self.priority = priority  # None: SCHED_OTHER

    def spawn(self, argv: list[str], cpu: int | None) -> Any:
        import subprocess

        priority = self.priority

        def prepare() -> None:
            if priority is not None:
                os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
            if cpu is not None:
                os.sched_setaffinity(0, {cpu})

        err = open(self.path("stderr"), "w+")  # noqa: SIM115 - closed in finish()
        proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=err, text=True,
                                env=self.env, preexec_fn=prepare)
        proc.err_file = err  # type: ignore[attr-defined]
        self.children.append(proc)
        return proc


def case_counts(args: argparse.Namespace, shape: str) -> tuple[int, int]:
    """(counted samples, warm-up cycles) of one case."""
    rate = SHAPES[shape]
    if args.quick:
        return int(QUICK_SECONDS * rate), int(0.2 * rate)
    if shape == "pingpong":
        return FULL_PINGPONG, int(rate)
    return int(args.control_seconds * rate), int(rate)


def run_case(runner: RtRunner, bin_dir: Path, transport: str, shape: str, name: str,
             count: int, warmup: int, cpus: tuple[int | None, int | None]) -> Record:
    prog = str(bin_dir / f"rt_{transport}")
    out = runner.path("rec")
    rate = str(SHAPES[shape])
    spin = [str(SPIN_US)] if transport == "iox" else []
    pong = [prog, "pong", name, shape, str(count + warmup), str(warmup), *spin]
    ping = [prog, "ping", name, shape, rate, str(count), str(warmup), str(out), *spin]
    pong_out, ping_out = runner.pair(pong, ping, cpus, f"{transport} {shape}")
    return {**report.stats(out), "ping": last_json(ping_out), "pong": last_json(pong_out),
            "warmup": warmup}


def last_json(out: str) -> Record:
    result: Record = json.loads(out.strip().splitlines()[-1])
    return result


def run_all(args: argparse.Namespace, runner: RtRunner, iox: Iceoryx,
            cpus: tuple[int | None, int | None], names: dict[str, str]) -> list[Record]:
    records: list[Record] = []
    bin_dir = args.build_dir / "bench" / "realtime"
    for shape in SHAPES:
        count, warmup = case_counts(args, shape)
        for transport in report.TRANSPORTS:
            rec: Record = {"shape": shape, "transport": transport, "rate_hz": SHAPES[shape]}
            if transport == "iox" and not iox.available:
                records.append({**rec, "error": f"not measured: {iox.why_not}"})
                continue
            t0 = time.monotonic()
            try:
                rec.update(run_case(runner, bin_dir, transport, shape,
                                    f"{names[shape]}{transport}", count, warmup, cpus))
                log(f"  {shape} {transport}: {time.monotonic() - t0:.1f} s")
            except (CaseError, ValueError, KeyError, IndexError, OSError) as exc:
                log(f"  {shape} {transport}: ERROR {exc}")
                rec["error"] = str(exc)
            records.append(rec)
    return records


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split()))
    parser.add_argument("--quick", action="store_true",
                        help=f"{QUICK_SECONDS:g} s per case: a smoke run, not a measurement")
    parser.add_argument("--control-seconds", type=float, default=300.0,
                        help="length of each 1 kHz control pair case in a full run "
                             "(default 300: 300,000 samples)")
    parser.add_argument("--priority", type=int, default=80,
                        help="SCHED_FIFO priority of both sides (default 80)")
    parser.add_argument("--sched-other", action="store_true",
                        help="measure under SCHED_OTHER (what a process without rtprio gets)")
    parser.add_argument("--cpus", help="PONG,PING: the CPUs of the two sides (default: the "
                                       "last two usable CPUs; one CPU: both on it)")
    parser.add_argument("--no-stress", action="store_true", help="leave stress-ng out")
    parser.add_argument("--no-iceoryx", action="store_true", help="leave iceoryx out")
    parser.add_argument("--build-dir", type=Path, default=REPO / "build" / "release")
    parser.add_argument("--json", type=Path,
                        default=REPO / "bench" / "results" / "realtime.json",
                        help="where the results go (the table beside it as .txt)")
    return parser.parse_args()


def placement(args: argparse.Namespace) -> tuple[tuple[int | None, int | None], str]:
    usable = sorted(os.sched_getaffinity(0))
    if args.cpus:
        pong, ping = (int(x) for x in args.cpus.split(","))
    else:
        pong, ping = (usable[-2], usable[-1]) if len(usable) > 1 else (usable[0], usable[0])
    why_not = can_pin([pong, ping])
    if why_not:
        return (None, None), f"not pinned: {why_not}"
    return (pong, ping), f"pong on CPU {pong}, ping on CPU {ping} (affinity)"


def main() -> int:
    args = parse_args()
    missing = [p for p in ("rt_ln", "rt_futex")
               if not (args.build_dir / "bench" / "realtime" / p).exists()]
    if missing:
        log(f"bench_realtime: {', '.join(missing)} missing: build them with `scons -j2`")
        return 2
    why_fifo = "--sched-other" if args.sched_other else fifo_allowed(args.priority)
    priority = None if why_fifo else args.priority
    sched_text = (f"SCHED_FIFO priority {args.priority}" if priority is not None
                  else f"SCHED_OTHER (SCHED_FIFO not applied: {why_fifo})")
    cpus, pin_text = placement(args)
    started = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    serial = f"{os.getpid()}"
    names = {shape: f"{PREFIX}.{shape}{serial}" for shape in SHAPES}
    scope_topics = [f"{names['pingpong']}ln.ping:counter", f"{names['control']}ln.state:cycle"]
    with tempfile.TemporaryDirectory(prefix="ln_bench_realtime_") as tmp_name:
        tmp = Path(tmp_name)
        bg = Background(tmp)
        iox = (Iceoryx(args.build_dir / "bench" / "realtime" / "rt_iox", why_not="--no-iceoryx")
               if args.no_iceoryx else
               Iceoryx.start(args.build_dir / "bench" / "realtime" / "rt_iox", tmp,
                             [64, 4096], {}))
        try:
            bg.start_manager()
            bg.start_extras(scope_topics, not args.no_stress)
            time.sleep(1.0)  # stress-ng and the scope get going
            runner = RtRunner(tmp, bg.env, priority)
            log(f"cases ({sched_text}; {pin_text})")
            try:
                records = run_all(args, runner, iox, cpus, names)
            finally:
                runner.kill_all()
        finally:
            background = bg.stop()
            iox.stop()
    goals = [report.goal(records, shape) for shape in SHAPES]
    head = [f"scheduling: {sched_text}; mlockall: called by each program (libln and ln_daemon "
            f"offer none); placement: {pin_text}",
            "load: " + "; ".join(f"{k}: {v}" for k, v in bg.parts.items()),
            f"background at the end: {background}",
            f"samples per case: pingpong {case_counts(args, 'pingpong')[0]} at 10 kHz, control "
            f"{case_counts(args, 'control')[0]} at 1 kHz"
            + ("; --quick: a smoke run, the numbers are not a measurement" if args.quick else "")]
    text = [*head, "", *report.table(records), "", *report.goals_table(goals)]
    print("\n".join(text))
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.with_suffix(".txt").write_text("\n".join(text) + "\n")
    args.json.write_text(json.dumps({
        **run_facts(started, args.quick), "scheduling": sched_text,
        "fifo_priority": priority, "placement": pin_text, "cpus": cpus,
        "stress_ng": STRESS if not args.no_stress else None, "background": bg.parts,
        "background_end": background, "iceoryx": iox.version, "iceoryx_why_not": iox.why_not,
        "goal": f"links_and_nodes p99.99 latency <= {report.GOAL_RATIO}x the raw futex floor's "
                "under the same load; max reported honestly",
        "cases": records, "goals": goals}, indent=2) + "\n")
    print(f"\nwrote {args.json} and {args.json.with_suffix('.txt')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
