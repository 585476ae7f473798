"""Benchmark of topics: latency, throughput and publish cost of links_and_nodes beside a raw
futex floor, a raw shared-memory ring (the zero-copy floor), pyzmq and, where installed,
iceoryx and iceoryx2, in one run with its own ln_manager (and iox-roudi; builds nothing: run
scons first); large messages both touched (first and last 8 bytes) and written whole (the
full-payload set, alone with --only full).  Prints tables and the goals with PASS/MISS, writes
bench/results/topics.json (or topics_full.json) and the printed tables beside it, exits 0
either way."""

from __future__ import annotations

import argparse
import importlib.metadata
import importlib.util
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import topics_full as full
import topics_report as report
from topics_peers import Iceoryx, iceoryx2_status
from topics_run import CaseError, Manager, Runner, can_pin, run_facts, warn_leftover

REPO = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
PROGRAMS = ("lat_ln", "lat_futex", "thr_ln", "pub_cost", "ring_floor")
MIB = 1 << 20
SIZES = [64, 4096, MIB, 4 * MIB, 16 * MIB, 64 * MIB]
# size -> (round trips, warm-up); fewer for MiB sizes, where a copy takes milliseconds
LAT_ITERATIONS = {64: (20000, 2000), 4096: (20000, 2000), MIB: (2000, 200),
                  4 * MIB: (1000, 100), 16 * MIB: (300, 30), 64 * MIB: (100, 10)}
ZMQ_MAX_SIZE = 4 * MIB  # pyzmq's four copies of 16 and 64 MiB would take most of the run
COPY_KEYS = ("futex", "ln_c", "ln_py", "zmq")  # latency cases that copy the whole sample
# zero-copy throughput: sizes, queue depth (ring slots - 1) and how long each case publishes
ZC_SIZES = [64, MIB, 4 * MIB, 16 * MIB, 64 * MIB]
ZC_BUFFERS = {64: 256, MIB: 16, 4 * MIB: 16, 16 * MIB: 8, 64 * MIB: 4}
ZC_SECONDS = 2.0
ZC_COUNT = 10**9  # never reached: the time limit ends a case
SPIN_US = 20  # the iceoryx peer spins before it sleeps, as libln's default spin_us
THR_SIZES = [64, 4096, 1 << 20]
THR_COUNT_C = {64: 2_000_000, 4096: 400_000, 1 << 20: 4000}
THR_COUNT_PY = {64: 300_000, 4096: 150_000, 1 << 20: 3000}
THR_BUFFERS = {64: 1024, 4096: 1024, 1 << 20: 64}
PUB_COST = (2_000_000, 7)  # writes per round, rounds
Record = dict[str, Any]
Cpus = tuple[int | None, int | None]  # (server/pong, client/ping); None: the scheduler's choice


def log(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


class Bench:
    """The cases: each starts its programs through the runner and returns one record."""

    def __init__(self, args: argparse.Namespace, runner: Runner, zmq: bool, iox: Iceoryx,
                 iox2: bool) -> None:
        self.bin = args.build_dir / "bench" / "topics"
        self.scale = 10 if args.quick else 1
        self.runner = runner
        self.zmq = zmq
        self.iox = iox.available
        self.iox2 = iox2
        self.py = [sys.executable]

    def has(self, key: str, size: int) -> bool:
        """Whether a transport takes part at this size in this run."""
        if self.scale > 1 and size > 4 * MIB and key in COPY_KEYS:
            return False  # --quick: copies of 16 and 64 MiB take seconds
        if key == "zmq":
            return self.zmq and size <= ZMQ_MAX_SIZE
        return {"iox": self.iox, "iox2": self.iox2, "iox_full": self.iox,
                "iox2_full": self.iox2}.get(key, True)

    def n(self, count: int, floor: int = 10) -> int:
        return max(floor, count // self.scale)

    def latency_case(self, key: str, size: int, cpus: Cpus) -> Record:
        count, warmup = (self.n(c) for c in LAT_ITERATIONS[size])
        out = self.runner.path("rtt")
        name = f"bench.lat{self.runner.serial}"
        total = str(count + warmup)
        tail = [str(count), str(warmup), str(out)]
        if key == "futex":
            pong_cpu = [] if cpus[0] is None or cpus[0] == cpus[1] else [str(cpus[0])]
            self.runner.single([str(self.bin / "lat_futex"), str(size), *tail, *pong_cpu],
                               cpus[1])
            return {**report.one_way_stats(out), "warmup": warmup,
                    "same_cpu": self.runner.same_cpu}
        if key in ("floor_zc", "floor_full"):
            pong_cpu = [] if cpus[0] is None or cpus[0] == cpus[1] else [str(cpus[0])]
            mode = ["full"] if key == "floor_full" else []
            got = last_json(self.runner.single([str(self.bin / "ring_floor"), "lat", str(size),
                                                *tail, *pong_cpu, *mode], cpus[1]))
            faults = {"ping_minflt": got["ping_minflt"], "pong_minflt": got["pong_minflt"]}
        else:
            pong, ping = self.latency_argv(key, size, name, [total, str(warmup)], tail)
            pong_out, ping_out = self.runner.pair(pong, ping, cpus, key)
            faults = {}
            if key != "zmq":
                faults = {"ping_minflt": last_json(ping_out)["minflt"],
                          "pong_minflt": last_json(pong_out)["minflt"]}
        per_sample = {f"{k}_per_sample": v / count for k, v in faults.items()}
        return {**report.one_way_stats(out), "warmup": warmup,
                "same_cpu": self.runner.same_cpu, **faults, **per_sample}

    def latency_argv(self, key: str, size: int, name: str, pong_tail: list[str],
                     tail: list[str]) -> tuple[list[str], list[str]]:
        """The pong and ping command lines of a two-process latency case."""
        full_mode = ["full"] if key.endswith("_full") else []
        if key in ("ln_c", "ln_c_zc", "ln_c_full"):
            prog, mode = str(self.bin / "lat_ln"), {"ln_c_zc": "zc", "ln_c_full": "full"}.get(
                key, "copy")
            return ([prog, "pong", name, str(size), mode, *pong_tail],
                    [prog, "ping", name, str(size), mode, *tail])
        if key in ("iox", "iox_full"):
            prog, spin = str(self.bin / "iox_bench"), str(SPIN_US)
            return ([prog, "pong", name, str(size), *pong_tail, spin, *full_mode],
                    [prog, "ping", name, str(size), *tail, spin, *full_mode])
        if key in ("ln_py", "ln_py_full", "iox2_full"):
            script = str(HERE / ("py_iox2.py" if key == "iox2_full" else "py_ln.py"))
            return ([*self.py, script, "pong", name, str(size), *pong_tail, *full_mode],
                    [*self.py, script, "ping", name, str(size), *tail, *full_mode])
        script, where = str(HERE / "py_zmq.py"), f"ipc://{self.runner.path('zmq')}.sock"
        return ([*self.py, script, "pong", where, str(size), pong_tail[0]],
                [*self.py, script, "ping", where, str(size), *tail])

    def throughput_case(self, key: str, mode: str, size: int) -> Record:
        count = self.n(THR_COUNT_C[size] if key == "ln_c" else THR_COUNT_PY[size], 100)
        name = f"bench.thr{self.runner.serial}"
        self.runner.serial += 1
        if key == "ln_c":
            prog = str(self.bin / "thr_ln")
            sub = [prog, "sub", name, str(size), str(count), str(THR_BUFFERS[size])]
            pub = [prog, "pub", name, str(size), str(count), mode]
        elif key == "ln_py":
            script = str(HERE / "py_ln.py")
            sub = [*self.py, script, "sub", name, str(size), str(count), str(THR_BUFFERS[size])]
            pub = [*self.py, script, "pub", name, str(size), str(count), mode]
        else:
            script, addr = str(HERE / "py_zmq.py"), f"ipc://{self.runner.path('zmq')}.sock"
            recv_role = "pull" if mode == "push" else "sub"
            sub = [*self.py, script, recv_role, addr, str(size), str(count)]
            pub = [*self.py, script, mode, addr, str(size), str(count)]
        sub_out, pub_out = self.runner.pair(sub, pub, (None, None), f"{key} {mode}")
        got = json.loads(sub_out.strip().splitlines()[-1])
        sent = json.loads(pub_out.strip().splitlines()[-1])
        rate = got["received"] / got["elapsed_s"] if got["elapsed_s"] > 0 else 0.0
        return {"sent": sent["sent"], "received": got["received"],
                "lost": sent["sent"] - got["received"], "overruns": got["overruns"],
                "disorder": got["disorder"], "elapsed_s": got["elapsed_s"], "recv_rate": rate,
                "gb_per_s": rate * size / 1e9, "send_rate": sent["sent"] / sent["elapsed_s"],
                "buffers": THR_BUFFERS[size] if key != "zmq" else None}

    def zc_throughput_case(self, key: str, size: int) -> Record:
        """Zero-copy publisher as fast as it can for ZC_SECONDS into a queued subscriber that
        keeps up or holds it back (no loss by design): loan, first and last 8 bytes, commit."""
        buffers = ZC_BUFFERS[size]
        warm = 2 * (buffers + 1)  # faults are counted after two laps of the ring
        seconds = ZC_SECONDS / self.scale
        name = f"bench.zc{self.runner.serial}"
        self.runner.serial += 1
        common = [str(size), str(ZC_COUNT)]
        mode = "full" if key.endswith("_full") else "zc"
        if key in ("floor_zc", "floor_full"):
            got = last_json(self.runner.single(
                [str(self.bin / "ring_floor"), "thr", *common, str(buffers), str(warm),
                 str(seconds), mode], None))
            sent = {"sent": got["sent"], "elapsed_s": got["send_elapsed_s"],
                    "minflt": got["pub_minflt"], "fault_samples": got["fault_samples"]}
            got = {"received": got["received"], "overruns": 0, "disorder": 0,
                   "elapsed_s": got["elapsed_s"], "minflt": got["sub_minflt"],
                   "fault_samples": got["fault_samples"]}
        else:
            if key in ("ln_c_zc", "ln_c_full"):
                prog = str(self.bin / "thr_ln")
                sub = [prog, "sub", name, *common, str(buffers), mode, str(warm)]
                pub = [prog, "pub", name, *common, "wait", mode, str(warm), str(seconds)]
            elif key in ("ln_py_zc", "ln_py_full"):
                script = str(HERE / "py_ln.py")
                sub = [*self.py, script, "sub", name, *common, str(buffers), mode, str(warm)]
                pub = [*self.py, script, "pub", name, *common, "wait", mode, str(warm),
                       str(seconds)]
            elif key in ("iox", "iox_full"):
                prog = str(self.bin / "iox_bench")
                sub = [prog, "sub", name, *common, str(buffers), str(warm), str(SPIN_US), mode]
                pub = [prog, "pub", name, *common, str(warm), str(seconds), mode]
            else:  # iox2, iox2_full
                script = str(HERE / "py_iox2.py")
                sub = [*self.py, script, "sub", name, *common, str(buffers), str(warm), mode]
                pub = [*self.py, script, "pub", name, *common, str(buffers), str(warm),
                       str(seconds), mode]
            sub_out, pub_out = self.runner.pair(sub, pub, (None, None), f"{key} {mode}")
            got, sent = last_json(sub_out), last_json(pub_out)
        rate = got["received"] / got["elapsed_s"] if got["elapsed_s"] > 0 else 0.0
        return {"sent": sent["sent"], "received": got["received"],
                "lost": sent["sent"] - got["received"], "overruns": got["overruns"],
                "disorder": got["disorder"], "elapsed_s": got["elapsed_s"], "recv_rate": rate,
                "gb_per_s": rate * size / 1e9, "send_rate": sent["sent"] / sent["elapsed_s"],
                "buffers": buffers, "seconds": seconds,
                "pub_minflt": sent["minflt"], "sub_minflt": got["minflt"],
                "pub_minflt_per_sample": per(sent["minflt"], sent["fault_samples"]),
                "sub_minflt_per_sample": per(got["minflt"], got["fault_samples"])}

    def pub_cost(self) -> Record:
        count, rounds = self.n(PUB_COST[0], 1000), PUB_COST[1] if self.scale == 1 else 3
        argv = [str(self.bin / "pub_cost"), "bench.cost", "64", str(count), str(rounds)]
        out = self.runner.finish(self.runner.spawn(argv, None), "pub_cost")
        return {**json.loads(out.strip().splitlines()[-1]), "count": count, "rounds": rounds}


def last_json(out: str) -> Record:
    """The last line of a program's output, which is its JSON result."""
    result: Record = json.loads(out.strip().splitlines()[-1])
    return result


def per(faults: int, samples: int) -> float | None:
    return faults / samples if samples else None


def attempt(what: str, fn: Any, *args: Any) -> Record:
    t0 = time.monotonic()
    try:
        rec = fn(*args)
    except (CaseError, ValueError, KeyError, IndexError, OSError) as exc:
        log(f"  {what}: ERROR {exc}")
        return {"error": str(exc)}
    log(f"  {what}: {time.monotonic() - t0:.1f} s")
    return rec


def placements(usable: list[int], pin_cpu: int) -> tuple[dict[str, tuple[Cpus, list[int]]], str]:
    """Where the two processes of a latency case run: name -> (cpus, sizes); and a note."""
    result: dict[str, tuple[Cpus, list[int]]] = {"sched": ((None, None), SIZES)}
    other = [c for c in usable if c != pin_cpu]
    why_not = can_pin([pin_cpu, *other[:1]])
    if why_not:
        return result, f"pinning unavailable: {why_not}"
    result["pinned"] = ((pin_cpu, pin_cpu), SIZES)
    if other:  # context: what a wake-up across CPUs costs here
        result["split"] = ((other[0], pin_cpu), SIZES[:1])
    return result, "available (sched_setaffinity)"


def run_all(bench: Bench, where: dict[str, tuple[Cpus, list[int]]]
            ) -> tuple[list[Record], list[Record], list[Record], Record]:
    log("publish cost")
    cost = attempt("pub_cost", bench.pub_cost)
    latency: list[Record] = []
    for placement, (cpus, sizes) in where.items():
        log(f"latency, {placement}")
        for size in sizes:  # all transports of one size close together in time
            for key in report.LATENCY:
                if not bench.has(key, size):
                    continue
                rec = attempt(f"{report.size_label(size)} {key}", bench.latency_case, key, size,
                              cpus)
                latency.append({"size": size, "transport": key, "placement": placement, **rec})
    log("throughput")
    throughput: list[Record] = []
    for size in THR_SIZES:
        for key, mode in report.THROUGHPUT:
            if key == "zmq" and not bench.zmq:
                continue
            rec = attempt(f"{report.size_label(size)} {key} {mode}", bench.throughput_case,
                          key, mode, size)
            throughput.append({"size": size, "transport": key, "mode": mode, **rec})
    log("zero-copy throughput")
    zc: list[Record] = []
    sizes = ZC_SIZES if bench.scale == 1 else [64, 4 * MIB, 64 * MIB]
    for size in sizes:  # all systems of one size close together in time
        for key in report.ZC_THROUGHPUT:
            if not bench.has(key, size):
                continue
            rec = attempt(f"{report.size_label(size)} {key} zc", bench.zc_throughput_case, key,
                          size)
            zc.append({"size": size, "transport": key, **rec})
    return latency, throughput, zc, cost


def run_full(bench: Bench, where: dict[str, tuple[Cpus, list[int]]], reps: int
             ) -> tuple[list[Record], list[Record]]:
    """The full-payload set, `reps` times with the order of the systems rotated from one
    repetition to the next: latency in the placements the goals are judged on, then
    zero-copy throughput.  Every repetition's record (its number in "rep")."""
    latency: list[Record] = []
    zc: list[Record] = []
    for rep in range(reps):
        lat_keys = rotated(list(full.LATENCY), rep)
        for placement, (cpus, _sizes) in where.items():
            if placement not in full.PLACEMENTS:
                continue
            log(f"full payload: latency, {placement}, repetition {rep + 1}/{reps}")
            for size in full.SIZES:  # all systems of one size close together in time
                for key in (k for k in lat_keys if bench.has(k, size)):
                    rec = attempt(f"{report.size_label(size)} {key}", bench.latency_case, key,
                                  size, cpus)
                    latency.append({"size": size, "transport": key, "placement": placement,
                                    "rep": rep, **rec})
        log(f"full payload: zero-copy throughput, repetition {rep + 1}/{reps}")
        for size in full.SIZES:
            for key in (k for k in rotated(list(full.ZC_THROUGHPUT), rep) if bench.has(k, size)):
                rec = attempt(f"{report.size_label(size)} {key}", bench.zc_throughput_case, key,
                              size)
                zc.append({"size": size, "transport": key, "rep": rep, **rec})
    return latency, zc


def rotated(items: list[str], by: int) -> list[str]:
    by %= len(items)
    return items[by:] + items[:by]


def git_head(tree: Path) -> str | None:
    """The commit a tree is at (read-only), to tell runs of different commits apart."""
    try:
        out = subprocess.run(["git", "-C", str(tree), "rev-parse", "--short", "HEAD"],
                             capture_output=True, text=True, timeout=10)
    except OSError:
        return None
    return out.stdout.strip() or None


GOALS_TEXT = ("goals: C 64 B p50 <= 1.2x futex floor; zero-copy 4 MiB p50 <= iceoryx and <= "
              "1.5x zero-copy 64 B;\n       Python 64 B p50 <= 0.5x pyzmq; Python 64 B queued "
              "throughput >= 2x pyzmq with zero loss;\n       Python zero-copy 4 MiB throughput "
              ">= iceoryx2; no minor page faults per sample in steady state;\n       publish "
              "with no waiting reader <= 100 ns\n")
FULL_GOALS_TEXT = ("goals (full payload): C zero-copy 4 MiB p50 <= 1.1x the futex floor and <= "
                   "iceoryx, 1 MiB <= iceoryx;\n       Python zero-copy throughput at 1 and 4 "
                   "MiB >= iceoryx2 (lossless), latency <= iceoryx2")


def parse_args() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split()))
    parser.add_argument("--quick", action="store_true",
                        help="a tenth of the iterations: a smoke run, not a measurement")
    parser.add_argument("--only", choices=["full"],
                        help="full: only the full-payload set (large messages written whole, "
                        "1 and 4 MiB), a few minutes; results to topics_full.json")
    parser.add_argument("--reps", type=int,
                        help="repetitions of the full-payload set (default 3, --quick 1)")
    parser.add_argument("--cpu", type=int, help="CPU for the pinned runs (default: the last)")
    parser.add_argument("--checkout", type=Path, default=REPO,
                        help="the tree whose build (CHECKOUT/build/release) and Python package "
                        "(CHECKOUT/python) are measured: another worktree, e.g. an older commit "
                        "(default: this one)")
    parser.add_argument("--build-dir", type=Path,
                        help="SCons variant directory with bench/topics/ "
                        "(default: CHECKOUT/build/release)")
    parser.add_argument("--json", type=Path,
                        help="where the results go (bench/results/topics.json, with --only "
                        "full topics_full.json); the printed tables go beside it (.txt)")
    parser.add_argument("--no-peers", action="store_true",
                        help="leave out iceoryx and iceoryx2 even where they are installed")
    args = parser.parse_args()
    if args.reps is None:
        args.reps = 1 if args.quick else 3
    if args.reps < 1:
        parser.error("--reps must be at least 1")
    if args.json is None:
        stem = "topics_full" if args.only == "full" else "topics"
        args.json = REPO / "bench" / "results" / f"{stem}.json"
    args.checkout = args.checkout.resolve()
    if args.build_dir is None:
        args.build_dir = args.checkout / "build" / "release"
    if args.cpu is not None and args.cpu not in os.sched_getaffinity(0):
        parser.error(f"--cpu {args.cpu} is not one of the usable CPUs")
    return args


def measure(args: argparse.Namespace, bench_args: tuple[bool, bool],
            where: dict[str, tuple[Cpus, list[int]]]) -> tuple[Record, Iceoryx, list[str]]:
    """Every case of the run, with its own manager and iox-roudi (stopped at the end)."""
    has_zmq, has_iox2 = bench_args
    results: Record = {}
    with tempfile.TemporaryDirectory(prefix="ln_bench_topics_") as tmp_name:
        tmp = Path(tmp_name)
        iox_program = args.build_dir / "bench" / "topics" / "iox_bench"
        iox = (Iceoryx(iox_program, why_not="--no-peers") if args.no_peers
               else Iceoryx.start(iox_program, tmp, full.SIZES if args.only else SIZES,
                                  ZC_BUFFERS))
        manager = Manager.start(tmp)
        runner = Runner(tmp, manager.process.env)  # LN_MANAGER and LN_RUNTIME_DIR set
        try:
            bench = Bench(args, runner, has_zmq, iox, has_iox2)
            if args.only != "full":
                (results["latency"], results["throughput"], results["zero_copy_throughput"],
                 results["publish_cost"]) = run_all(bench, where)
            results["full_latency"], results["full_zero_copy_throughput"] = run_full(
                bench, where, args.reps)
        finally:
            runner.kill_all()
            leftover = manager.stop()
            iox.stop()
    return results, iox, leftover


def main() -> int:
    args = parse_args()
    # The manager and every Python child import links_and_nodes (and so libln) of CHECKOUT.
    python_dir = args.checkout / "python"
    os.environ["PYTHONPATH"] = os.pathsep.join(
        [str(python_dir), *filter(None, [os.environ.get("PYTHONPATH")])])

    missing = [p for p in PROGRAMS if not (args.build_dir / "bench" / "topics" / p).exists()]
    if missing:
        print(f"bench_topics: {', '.join(missing)} missing under {args.build_dir}/bench/topics: "
              "build them first with `scons -j2`", file=sys.stderr)
        return 2
    has_zmq = importlib.util.find_spec("zmq") is not None
    usable = sorted(os.sched_getaffinity(0))
    pin_cpu = args.cpu if args.cpu is not None else usable[-1]
    where, pin_text = placements(usable, pin_cpu)
    names = {"sched": "the scheduler's placement", "pinned": f"both on CPU {pin_cpu}"}
    if "split" in where:
        names["split"] = f"pong on CPU {where['split'][0][0]}, ping on CPU {pin_cpu}"
    load_start = os.getloadavg()
    started = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    iox2_version, iox2_why = (None, "--no-peers") if args.no_peers else iceoryx2_status()

    results, iox, leftover = measure(args, (has_zmq, iox2_version is not None), where)
    full_lat = full.latency_medians(results["full_latency"])
    full_zc = full.zc_medians(results["full_zero_copy_throughput"])
    goals = full.goals(full_lat, full_zc, list(where))
    cost = results.get("publish_cost", {})
    if args.only != "full":
        goals = report.goals(results["latency"], results["throughput"],
                             results["zero_copy_throughput"], cost) + goals
    zmq_version = importlib.metadata.version("pyzmq") if has_zmq else None

    lines = [(GOALS_TEXT if args.only != "full" else "") + FULL_GOALS_TEXT,
             f"measured: {args.checkout} ({git_head(args.checkout)}), build {args.build_dir}",
             f"cpu: os.cpu_count()={os.cpu_count()}, usable={len(usable)} {usable}; "
             f"pinning: {pin_text}"]
    perf = cost.get("perf_counters")
    lines.append(f"perf counters: {'available' if perf else 'unavailable'}"
                 + (f" ({cost.get('perf_counters_error')})" if perf is False else "")
                 + f"; load average at start {load_start[0]:.2f}, at end "
                 f"{os.getloadavg()[0]:.2f}")
    lines.append(f"python {platform.python_version()}, "
                 + (f"pyzmq {zmq_version}" if has_zmq else "pyzmq not installed: its rows are "
                    "missing")
                 + ("; --quick: a smoke run, the numbers are not a measurement" if args.quick
                    else ""))
    iox_text = f"{iox.version or '?'} (own iox-roudi)" if iox.available else iox.why_not
    lines.append(f"iceoryx: {iox_text}; iceoryx2: {iox2_version or iox2_why}")
    tables = []
    if args.only != "full":
        latency, zc = results["latency"], results["zero_copy_throughput"]
        tables += [report.latency_tables(latency, SIZES, {k: names[k] for k in where}),
                   report.throughput_table(results["throughput"]),
                   report.zc_throughput_table(zc), report.faults_table(latency, zc),
                   report.summary_table(latency, zc, ZC_SIZES), report.pub_cost_table(cost)]
    tables += [full.latency_table(full_lat, {k: names[k] for k in where}, args.reps),
               full.zc_table(full_zc, args.reps, ZC_SECONDS / (10 if args.quick else 1)),
               report.goals_table(goals)]
    for table in tables:
        lines += ["", *table]
    print("\n".join(lines))
    warn_leftover(leftover)

    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.with_suffix(".txt").write_text("\n".join(lines) + "\n")
    args.json.write_text(json.dumps({
        **run_facts(started, args.quick), "only": args.only, "reps": args.reps,
        "usable_cpus": usable, "pinning": pin_text,
        "placements": {k: {"cpus": v[0], "sizes": v[1], "what": names[k]} for k, v in where.items()},
        "perf_counters": perf, "loadavg_start": load_start, "loadavg_end": os.getloadavg(),
        "pyzmq": zmq_version, "checkout": str(args.checkout), "commit": git_head(args.checkout),
        "build_dir": str(args.build_dir),
        "iceoryx": iox.version if iox.available else None, "iceoryx_why_not": iox.why_not,
        "roudi_mempools": iox.config, "iceoryx2": iox2_version, "iceoryx2_why_not": iox2_why,
        **results, "full_latency_medians": full_lat, "full_zero_copy_medians": full_zc,
        "goals": goals, "leftover_segments": leftover,
    }, indent=2) + "\n")
    print(f"\nwrote {args.json} and {args.json.with_suffix('.txt').name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
