"""Benchmark of topics between hosts (issue 36, large messages at the speed of the wire):
ping-pong latency at 64 B, 64 KiB, 1 MiB and 4 MiB and throughput of the large sizes of
links_and_nodes from host a to host b (emulated: network namespaces on a bridge,
tests/python/netlab.py) beside raw UDP and TCP between the same hosts and beside ln on one
host, in alternating rounds, with the CPU time per MB on each host; ln's throughput as fast
as possible and paced at its goal share of raw TCP's rate (builds nothing: run scons first;
needs root).  Prints tables and the goals with PASS/MISS, writes bench/results/network.json,
exits 0 either way.
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
sys.path.insert(0, str(HERE.parent / "topics"))  # percentiles of raw round trips
sys.path.insert(0, str(REPO / "tests" / "python"))  # the lab
for _p in (REPO, REPO / "python"):
    if str(_p) not in sys.path:
        sys.path.insert(0, str(_p))

import network_report as report  # noqa: E402
from netlab import NetLab, netlab_available  # noqa: E402
from network_cases import RAW_PORT, CaseError, Lab, Proc, json_line  # noqa: E402
from topics_report import one_way_stats  # noqa: E402

PROGRAMS = ("pingpong", "ln_pingpong")
MIB = report.MIB
# round trips per case (a tenth more as warm-up): fewer the larger, a few seconds each
LAT_COUNT = {64: 20000, 64 * report.KIB: 5000, MIB: 1000, 4 * MIB: 250}
# throughput: each case moves about THR_BYTES (2,000 1 MiB samples), at most THR_MAX samples
THR_BYTES, THR_MAX = 2000 * MIB, 20000
ROUNDS, QUICK_ROUNDS, QUICK_SCALE = 5, 2, 10
Record = dict[str, Any]


def log(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


class Bench:
    """The cases: each runs its pair in the lab and returns one record."""

    def __init__(self, lab: Lab, quick: bool) -> None:
        self.lab = lab
        scale = QUICK_SCALE if quick else 1
        self.lat = {size: (n // scale, n // scale // 10) for size, n in LAT_COUNT.items()}
        self.thr = {
            size: min(THR_MAX, THR_BYTES // size) // scale
            for size in sorted({s for s, _ in report.THROUGHPUT_CASES})
        }
        self.raw_rates: dict[int, list[float]] = {}  # raw TCP's msg/s so far, by size

    def unavailable(self, system: str) -> str | None:
        return self.lab.multihost_missing if system in report.TRANSPORT else None

    def latency(self, size: int, system: str) -> Record:
        count, warmup = self.lat[size]
        out = self.lab.path("rtt")
        tail = [str(size), str(count), str(warmup), str(out)]
        if system.startswith("raw_"):
            proto, prog = system[4:], self.lab.prog("pingpong")
            server = [prog, f"{proto}-echo", str(RAW_PORT)] + (
                [str(size)] if proto == "tcp" else []
            )
            _, text = self.lab.raw_pair(
                server, [prog, f"{proto}-ping", self.lab.b.address, str(RAW_PORT), *tail], system
            )
            result = json_line(text, system)
        else:
            manager, near, far = self.lab.ln_placement(system)
            mode = report.TRANSPORT.get(system, "default")
            prog = self.lab.prog("ln_pingpong")
            got = self.lab.managed(
                manager,
                [
                    Proc("pong", far, [prog, "pong", "bench", str(size), mode], ready=True),
                    Proc(
                        "ping",
                        near,
                        [prog, "ping", "bench", str(size), mode, str(count), str(warmup), str(out)],
                    ),
                ],
                ["ping"],
                system,
            )
            result = got["ping"]
        if result["round_trips"] == 0:
            raise CaseError(f"{system}: every round trip needed a resend")
        return {**one_way_stats(out), "warmup": warmup, "resent": result["resent"]}

    def pace(self, size: int, system: str) -> float:
        """Messages per second the source of `system` publishes at: 0 (as fast as it can),
        or for a paced case its share of raw TCP's rate (the median of this run so far)."""
        if system not in report.PACE:
            return 0.0
        if not self.raw_rates.get(size):
            raise CaseError(
                f"{system}: no raw TCP throughput of {report.size_label(size)} "
                "measured yet to pace at"
            )
        return report.PACE[system] * statistics.median(self.raw_rates[size])

    def throughput(self, size: int, system: str) -> Record:
        """CPU per MB: raw TCP's source (a) and sink (b); ln's the same programs plus the
        ln_daemon of their host, whose threads forward (ln on one host: all on a)."""
        count = self.thr[size]
        if system == "raw_tcp":
            prog = self.lab.prog("pingpong")
            got_text, sent_text = self.lab.raw_pair(
                [prog, "tcp-sink", str(RAW_PORT), str(size)],
                [prog, "tcp-source", self.lab.b.address, str(RAW_PORT), str(size), str(count)],
                system,
            )
            got, sent = json_line(got_text, "tcp-sink"), json_line(sent_text, "tcp-source")
            rec = report.throughput_stats(sent, got, size, {"a": sent["cpu_s"], "b": got["cpu_s"]})
            self.raw_rates.setdefault(size, []).append(rec["msgs_per_s"])
            return rec
        rate = self.pace(size, system)
        manager, near, far = self.lab.ln_placement(system)
        mode = report.TRANSPORT.get(system, "default")
        prog = self.lab.prog("ln_pingpong")
        before = self.lab.daemon_cpu_s()
        res = self.lab.managed(
            manager,
            [
                Proc("sink", far, [prog, "sink", "bench", str(size), mode, str(count)], ready=True),
                Proc(
                    "source",
                    near,
                    [prog, "source", "bench", str(size), mode, str(count), f"{rate:.3f}"],
                ),
            ],
            ["sink", "source"],
            system,
        )
        after = self.lab.daemon_cpu_s()
        got, sent = res["sink"], res["source"]
        daemon = {h: after[h] - before[h] for h in after}
        cpu: dict[str, float | None] = (
            {"a": daemon["a"] + sent["cpu_s"] + got["cpu_s"], "b": None}
            if system == "ln_local"
            else {"a": daemon["a"] + sent["cpu_s"], "b": daemon["b"] + got["cpu_s"]}
        )
        return {
            **report.throughput_stats(sent, got, size, cpu, rate or None),
            "cpu_daemon_a_s": daemon["a"],
            "cpu_daemon_b_s": daemon["b"],
            "cpu_source_s": sent["cpu_s"],
            "cpu_sink_s": got["cpu_s"],
        }


def figure(kind: str, rec: Record) -> str:
    """One case's main numbers for the progress log."""
    if kind == "latency":
        return f"p50 {rec['p50_us']:.2f} µs"
    cpu = "/".join(
        "-" if v is None else f"{v:,.0f}" for v in (rec["cpu_a_us_per_mb"], rec["cpu_b_us_per_mb"])
    )
    paced = f" at {rec['paced_msgs_per_s']:,.0f} msg/s" if rec["paced_msgs_per_s"] else ""
    return (
        f"{rec['mb_per_s']:,.0f} MB/s, lost {rec['lost']} of {rec['sent']}{paced}, "
        f"cpu a/b {cpu} µs/MB"
    )


def run_all(bench: Bench, rounds: int, only: set[str] | None = None) -> list[Record]:
    """Every round runs every case (of the systems in `only`, if given); the order rotates
    from round to round, so drifting background load does not always hit the same system."""
    cases = [("latency", s, sys_) for s, sys_ in report.LATENCY_CASES] + [
        ("throughput", s, sys_) for s, sys_ in report.THROUGHPUT_CASES
    ]
    if only:
        cases = [c for c in cases if c[2] in only]
    runs: list[Record] = []
    for rnd in range(rounds):
        log(f"round {rnd + 1}/{rounds}")
        k = rnd % len(cases)
        for kind, size, system in cases[k:] + cases[:k]:
            head = {"round": rnd, "kind": kind, "size": size, "system": system}
            why = bench.unavailable(system)
            if why:
                runs.append({**head, "unavailable": why})
                continue
            t0 = time.monotonic()
            try:
                rec = (bench.latency if kind == "latency" else bench.throughput)(size, system)
                log(
                    f"  {kind} {report.size_label(size)} {system}: {figure(kind, rec)} "
                    f"({time.monotonic() - t0:.1f} s)"
                )
            except (CaseError, ValueError, OSError) as exc:
                log(f"  {kind} {report.size_label(size)} {system}: ERROR {exc}")
                rec = {"error": str(exc)}
            runs.append({**head, **rec})
    return runs


def goal_text() -> str:
    tcp, udp = report.LARGE_GOALS["ln_tcp"], report.LARGE_GOALS["ln_udp"]
    return (
        f"goal (issue 36): ln 64 B p50 between hosts <= {report.GOAL_FACTOR:g}x the raw "
        f"floor of its transport + {report.GOAL_ADD_US:g} µs (UDP: raw UDP, TCP: raw TCP); "
        f"1 MiB over TCP: p50 <= {tcp['p50']:g}x raw TCP, MB/s >= {tcp['mb_per_s']:g}x raw "
        f"TCP; over UDP: p50 <= {udp['p50']:g}x raw TCP, MB/s >= {udp['mb_per_s']:g}x raw "
        f"TCP; paced at that share of raw TCP's msg/s, nothing lost; CPU per MB on each "
        f"host <= {report.CPU_GOAL:g}x raw TCP's (paced); 64 KiB and 4 MiB shown beside"
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split()))
    parser.add_argument(
        "--quick",
        action="store_true",
        help=f"{QUICK_ROUNDS} rounds of a tenth of everything: a smoke run, not a measurement",
    )
    parser.add_argument(
        "--rounds", type=int, help=f"rounds (default {ROUNDS}, --quick {QUICK_ROUNDS})"
    )
    parser.add_argument(
        "--force-multihost",
        action="store_true",
        help="run the ln a->b cases even where the multi-host system looks "
        "missing (to try a partial implementation)",
    )
    parser.add_argument(
        "--daemon-spin-us",
        type=int,
        default=0,
        help="ln_daemon --spin-us of both daemons (default 0: no polling)",
    )
    parser.add_argument(
        "--only",
        help="comma-separated systems to run, e.g. raw_tcp,ln_tcp,ln_tcp_paced (a paced "
        "case needs raw_tcp): for a look at one path, not a measurement of the goals",
    )
    parser.add_argument(
        "--security",
        choices=("none", "authenticate", "encrypt"),
        default=None,
        help="the instance's `security` level for the ln a->b cases (default: the "
        "instance default, authenticate)",
    )
    parser.add_argument(
        "--build-dir",
        type=Path,
        default=REPO / "build" / "release",
        help="SCons variant directory with bench/network/ (build/release)",
    )
    parser.add_argument(
        "--json",
        type=Path,
        default=REPO / "bench" / "results" / "network.json",
        help="where the results go (bench/results/network.json)",
    )
    args = parser.parse_args()
    rounds = args.rounds or (QUICK_ROUNDS if args.quick else ROUNDS)
    bin_dir = args.build_dir / "bench" / "network"
    missing = [p for p in PROGRAMS if not (bin_dir / p).exists()]
    if missing:
        print(
            f"bench_network: {', '.join(missing)} missing under {bin_dir}: build them "
            "first with `scons -j2`",
            file=sys.stderr,
        )
        return 2
    why = netlab_available()
    if why:
        print(f"bench_network: network namespaces unavailable: {why}", file=sys.stderr)
        return 2
    load_start = os.getloadavg()
    started = time.strftime("%Y-%m-%dT%H:%M:%S%z")

    with (
        tempfile.TemporaryDirectory(prefix="ln_bench_network_") as tmp,
        NetLab(Path(tmp)) as netlab,
    ):
        daemon_args = ("--spin-us", str(args.daemon_spin_us)) if args.daemon_spin_us else ()
        lab = Lab(netlab, bin_dir, args.force_multihost, daemon_args)
        lab.security = args.security
        bench = Bench(lab, args.quick)
        only = set(args.only.split(",")) if args.only else None
        unknown = sorted(
            (only or set()) - {s for _, s in report.THROUGHPUT_CASES + report.LATENCY_CASES}
        )
        if unknown:
            print(f"bench_network: unknown systems {', '.join(unknown)}", file=sys.stderr)
            return 2
        runs = run_all(bench, rounds, only)
        shm_left = lab.shm_left()
    summary = report.summarize(runs)
    goals = report.goals(summary)

    print(goal_text())
    print(
        f"hosts: network namespaces a, b, mgr on one bridge (veth), on {os.cpu_count()} "
        f"CPUs shared by all; ln_daemon --spin-us {args.daemon_spin_us}; security "
        f"{args.security or 'authenticate (default)'}; load average at start {load_start[0]:.2f}, at end "
        f"{os.getloadavg()[0]:.2f}; python {platform.python_version()}, kernel "
        f"{platform.release()}"
        + ("; --quick: a smoke run, the numbers are not a measurement" if args.quick else "")
    )
    if lab.multihost_missing:
        print(f"ln between hosts: NOT MEASURED, not available yet: {lab.multihost_missing}")
    for lines in (
        report.latency_tables(summary, bench.lat),
        report.throughput_tables(summary, bench.thr),
        report.goals_table(goals),
    ):
        print()
        print("\n".join(lines))
    if shm_left:
        print(f"\nwarning: segments left behind in /dev/shm: {shm_left}")

    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(
        json.dumps(
            {
                "started": started,
                "quick": args.quick,
                "machine": platform.machine(),
                "kernel": platform.release(),
                "python_version": platform.python_version(),
                "cpu_count": os.cpu_count(),
                "loadavg_start": load_start,
                "loadavg_end": os.getloadavg(),
                "rounds": rounds,
                "security": args.security or "authenticate",
                "daemon_spin_us": args.daemon_spin_us,
                "latency_counts": {str(k): v for k, v in bench.lat.items()},
                "throughput_counts": {str(k): v for k, v in bench.thr.items()},
                "pace": report.PACE,
                "multihost_missing": lab.multihost_missing,
                "runs": runs,
                "summary": summary,
                "goals": goals,
                "shm_left": shm_left,
            },
            indent=2,
        )
        + "\n"
    )
    print(f"\nwrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
