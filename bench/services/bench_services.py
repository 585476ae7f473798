"""Benchmark of services: call round trip of a 64-byte request and response through ln
services in C and Python beside a raw Unix-socket echo and pyzmq REQ/REP, in alternating rounds
with its own ln_manager (builds nothing: run scons first).  Prints tables and the goals with
PASS/MISS, writes bench/results/services.json, exits 0 either way.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import importlib.util
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
TOPICS = HERE.parent / "topics"
sys.path.insert(0, str(TOPICS))  # the process plumbing and pyzmq REQ/REP of bench/topics

import services_report as report  # noqa: E402
from topics_run import (  # noqa: E402
    CaseError,
    Manager,
    Runner,
    can_pin,
    run_facts,
    warn_leftover,
)

PROGRAMS = ("svc_echo_raw", "svc_ln")
COUNT, WARMUP, ROUNDS = 20000, 2000, 7  # calls per case, warm-up calls before them, rounds
QUICK_SCALE, QUICK_ROUNDS = 10, 3
Record = dict[str, Any]
Cpus = tuple[int | None, int | None]  # (server, client); None: the scheduler's choice


def log(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def python_ln_missing() -> str | None:
    """None if the Python service API is there, else what is missing."""
    try:
        import links_and_nodes as ln

        missing = [n for n in ("get_service", "get_service_provider",
                               "wait_and_handle_service_group_requests")
                   if not hasattr(ln.client, n)]
    except Exception as exc:  # noqa: BLE001 - any failure to load means "not available"
        return f"links_and_nodes does not load: {exc}"
    return f"ln.client has no {', '.join(missing)}" if missing else None


class Bench:
    """The cases: each starts a server and a client through the runner and returns one
    record of round-trip statistics."""

    def __init__(self, args: argparse.Namespace, runner: Runner) -> None:
        self.bin = args.build_dir / "bench" / "services"
        scale = QUICK_SCALE if args.quick else 1
        self.count, self.warmup = COUNT // scale, WARMUP // scale
        self.runner = runner
        self.py = [sys.executable]

    def case(self, system: str, cpus: Cpus) -> Record:
        out = self.runner.path("rtt")
        total = str(self.count + self.warmup)
        tail = [str(self.count), str(self.warmup), str(out)]
        name = f"bench.echo{self.runner.serial}"
        if system == "raw":
            prog, sock = str(self.bin / "svc_echo_raw"), f"{self.runner.path('echo')}.sock"
            server, client = [prog, "server", sock], [prog, "client", sock, *tail]
        elif system == "ln_c":
            prog = str(self.bin / "svc_ln")
            server, client = [prog, "provide", name, total], [prog, "call", name, *tail]
        elif system == "ln_py":
            script = str(HERE / "py_svc_ln.py")
            server = [*self.py, script, "provide", name, total]
            client = [*self.py, script, "call", name, *tail]
        else:  # the REQ/REP ping-pong of the topic benchmark, 64-byte messages
            script, addr = str(TOPICS / "py_zmq.py"), f"ipc://{self.runner.path('zmq')}.sock"
            server = [*self.py, script, "pong", addr, "64", total]
            client = [*self.py, script, "ping", addr, "64", *tail]
        self.runner.pair(server, client, cpus, system)
        return {**report.round_trip_stats(out), "warmup": self.warmup,
                "same_cpu": self.runner.same_cpu}


def placements(usable: list[int], pin_cpu: int) -> tuple[dict[str, Cpus], str]:
    """Where the two processes of a case run: name -> cpus; and a note on pinning."""
    why_not = can_pin([pin_cpu])
    if why_not:
        return {"sched": (None, None)}, f"pinning unavailable: {why_not}"
    return {"sched": (None, None), "pinned": (pin_cpu, pin_cpu)}, "available (sched_setaffinity)"


def run_all(bench: Bench, where: dict[str, Cpus], systems: list[str], rounds: int
            ) -> list[Record]:
    """Every round runs every system in every placement; the order of the systems rotates
    from round to round, so drifting background load does not always hit the same one."""
    runs: list[Record] = []
    for rnd in range(rounds):
        order = systems[rnd % len(systems):] + systems[:rnd % len(systems)]
        for placement, cpus in where.items():
            log(f"round {rnd + 1}/{rounds}, {placement}")
            for system in order:
                t0 = time.monotonic()
                try:
                    rec = bench.case(system, cpus)
                    log(f"  {system}: p50 {rec['p50_us']:.2f} µs "
                        f"({time.monotonic() - t0:.1f} s)")
                except (CaseError, ValueError, OSError) as exc:
                    log(f"  {system}: ERROR {exc}")
                    rec = {"error": str(exc)}
                runs.append({"round": rnd, "system": system, "placement": placement, **rec})
    return runs


def main() -> int:
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split()))
    parser.add_argument("--quick", action="store_true",
                        help=f"{QUICK_ROUNDS} rounds of a tenth of the calls: a smoke run, "
                             "not a measurement")
    parser.add_argument("--rounds", type=int, help=f"rounds (default {ROUNDS}, --quick "
                                                   f"{QUICK_ROUNDS})")
    parser.add_argument("--cpu", type=int, help="CPU for the pinned runs (default: the last)")
    parser.add_argument("--build-dir", type=Path, default=REPO / "build" / "release",
                        help="SCons variant directory with bench/services/ (build/release)")
    parser.add_argument("--json", type=Path,
                        default=REPO / "bench" / "results" / "services.json",
                        help="where the results go (bench/results/services.json)")
    args = parser.parse_args()
    rounds = args.rounds or (QUICK_ROUNDS if args.quick else ROUNDS)

    missing = [p for p in PROGRAMS if not (args.build_dir / "bench" / "services" / p).exists()]
    if missing:
        print(f"bench_services: {', '.join(missing)} missing under {args.build_dir}/bench/"
              "services: build them first with `scons -j2`", file=sys.stderr)
        return 2
    unavailable: dict[str, str] = {}
    if importlib.util.find_spec("zmq") is None:
        unavailable["zmq"] = "pyzmq is not installed"
    why = python_ln_missing()
    if why:
        unavailable["ln_py"] = f"the Python service API is missing ({why})"
    systems = [s for s in report.SYSTEMS if s not in unavailable]
    usable = sorted(os.sched_getaffinity(0))
    pin_cpu = args.cpu if args.cpu is not None else usable[-1]
    if pin_cpu not in usable:
        parser.error(f"--cpu {pin_cpu} is not one of the usable CPUs {usable}")
    where, pin_text = placements(usable, pin_cpu)
    names = {"sched": "the scheduler's placement", "pinned": f"both on CPU {pin_cpu}"}
    names = {k: names[k] for k in where}
    load_start = os.getloadavg()
    started = time.strftime("%Y-%m-%dT%H:%M:%S%z")

    with tempfile.TemporaryDirectory(prefix="ln_bench_services_") as tmp_name:
        tmp = Path(tmp_name)
        manager = Manager.start(tmp)
        runner = Runner(tmp, manager.process.env)  # LN_MANAGER and LN_RUNTIME_DIR set
        bench = Bench(args, runner)
        try:
            runs = run_all(bench, where, systems, rounds)
        finally:
            runner.kill_all()
            leftover = manager.stop()
    summary = report.summarize(runs)
    goals = report.goals(summary, list(where), unavailable)
    zmq_version = None if "zmq" in unavailable else importlib.metadata.version("pyzmq")

    print("goals: C ln p50 <= 1.5x the raw Unix echo p50; Python ln p50 < pyzmq REQ/REP p50 "
          "(each in every placement)")
    print(f"cpu: os.cpu_count()={os.cpu_count()}, usable={len(usable)} {usable}; "
          f"pinning: {pin_text}; load average at start {load_start[0]:.2f}, "
          f"at end {os.getloadavg()[0]:.2f}")
    print(f"python {platform.python_version()}"
          + (f", pyzmq {zmq_version}" if zmq_version else "")
          + ("; --quick: a smoke run, the numbers are not a measurement" if args.quick else ""))
    header = (f"call round trip, 64 B request + 64 B response, in µs: median over {rounds} "
              f"rounds of {bench.count:,} calls each (after {bench.warmup:,} warm-up); "
              "calls/s = calls / their summed round trips")
    for lines in (report.tables(summary, names, header, unavailable), report.goals_table(goals)):
        print()
        print("\n".join(lines))
    warn_leftover(leftover)

    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({
        **run_facts(started, args.quick), "usable_cpus": usable, "pinning": pin_text,
        "placements": {k: {"cpus": where[k], "what": v} for k, v in names.items()},
        "loadavg_start": load_start, "loadavg_end": os.getloadavg(), "pyzmq": zmq_version,
        "unavailable": unavailable, "count": bench.count, "warmup": bench.warmup,
        "rounds": rounds, "runs": runs, "summary": summary, "goals": goals,
        "leftover_segments": leftover,
    }, indent=2) + "\n")
    print(f"\nwrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
