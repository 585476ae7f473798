"""Benchmark of process start-up: `ln_manager -c` starting 50 trivial processes in a dependency
tree until all are ready, and stopping them, in alternating rounds with a shell script that
starts the same tree with no middleware (the floor).  Builds nothing: run scons first.
Prints tables and the goals with PASS/MISS, writes bench/results/startup.json, exits 0 either
way; checks at the end that no process, daemon, key file or segment is left.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
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
sys.path.insert(0, str(REPO / "python"))  # measure this checkout's manager, not an installed one

import startup_run as run  # noqa: E402

from links_and_nodes.manager.processes import daemon_keys as dk  # noqa: E402
from links_and_nodes.manager.processes import daemon_launch as dl  # noqa: E402
from links_and_nodes.manager.processes import daemon_wire as dw  # noqa: E402
from links_and_nodes.tools.scripting import ManagerError, connect  # noqa: E402

PROCESSES, ROUNDS, QUICK_ROUNDS = 50, 11, 2
GOAL_SECONDS, GOAL_RATIO = 1.5, 3.0  # all-ready (warm daemon); and over the shell floor
READY_LINE = r"all (\d+) processes ready"
NOT_READY_LINE = r"not all processes ready|failed"
Record = dict[str, Any]
IMPORTS = ("import links_and_nodes.manager.frontends.cli, links_and_nodes.manager.registry.core, "
           "links_and_nodes.manager.registry.server, links_and_nodes.manager.runner")

# measurement -> (label, what it is); the order of the table
MEASURES = {
    "mgr_ready": ("ln_manager -c: launch -> all ready", "warm daemon"),
    "mgr_to_first_start": ("  launch -> first process starting", "interpreter, imports, "
                           "config, daemon link"),
    "mgr_tree": ("  first starting -> last ready", "the dependency tree"),
    "mgr_report": ("  last ready -> 'all ready' line", ""),
    "mgr_hop": ("  a parent ready -> its child started", "median over the tree's edges"),
    "py_start": ("python -c pass", "for scale: interpreter start"),
    "py_imports": ("python -c 'import ...'", "for scale: the modules ln_manager -c loads"),
    "shell_ready": ("shell floor: launch -> all ready", "floor.sh, output through a FIFO"),
    "api_ready": ("scripting start + wait_ready", "manager already up"),
    "mgr_stop": ("scripting stop('all')", "dependents first"),
    "mgr_quit": ("scripting quit -> manager exited", "stops all, then exits"),
    "shell_stop": ("shell floor: kill + wait", "all at once"),
}


def log(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def ms(seconds: float | None) -> str:
    return "-" if seconds is None else f"{seconds * 1e3:.1f}"


class Bench:
    """The two systems: each method runs one round and returns its record of seconds."""

    def __init__(self, args: argparse.Namespace, tmp: Path, prog: Path) -> None:
        self.n = args.processes
        self.tmp = tmp
        self.prog = prog
        self.token = f"startbench{os.getpid()}x{uuid.uuid4().hex[:8]}"  # also the instances'
        self.serial = 0
        self.env = {**os.environ, "LN_RUNTIME_DIR": str(tmp / "runtime"),
                    "PYTHONPATH": os.pathsep.join(
                        [str(REPO / "python"), *filter(None, [os.environ.get("PYTHONPATH")])])}
        self.env.pop("LN_MANAGER", None)
        self.managers: list[run.Child] = []
        self.instances: list[str] = []

    def scratch(self, stem: str) -> Path:
        self.serial += 1
        path = self.tmp / f"{stem}{self.serial}"
        path.mkdir()
        return path

    def check_running(self, what: str) -> None:
        count = len(run.with_token(self.token))
        if count != self.n:
            raise run.CaseError(f"{what}: {count} of {self.n} processes running")

    def check_gone(self, what: str) -> None:
        """The processes are gone (reaped: a stop returns after their exit was seen)."""
        deadline = time.monotonic() + 2.0
        while run.with_token(self.token):
            if time.monotonic() > deadline:
                left = run.with_token(self.token)
                run.terminate_pids(left)
                raise run.CaseError(f"{what}: {len(left)} processes still running (killed)")
            time.sleep(0.01)

    def manager(self, daemon_port: int, key_file: Path) -> Record:
        """Launch ln_manager -c --start-all --wait-ready until its "all ready" line; then
        through the scripting API stop('all'), start + wait_ready, and quit."""
        work = self.scratch("mgr")
        instance = f"{self.token}r{self.serial}"
        self.instances.append(instance)
        port = run.free_port()
        lnc = work / "startup.lnc"
        run.write_lnc(lnc, instance, port, self.prog, self.token, self.n)
        env = {**self.env, "LN_ARBITER_PORT": str(daemon_port),
               "LN_DAEMON_KEY_FILE": str(key_file)}
        argv = [sys.executable, "-m", "links_and_nodes.manager", "-c", str(lnc), "--start-all",
                "--wait-ready", "--no-console", "--log-level", "warning"]
        wall0, t0 = time.time(), time.monotonic()
        child = run.Child(argv, env, work / "manager.log")
        self.managers.append(child)
        try:
            t_ready, match = child.expect(READY_LINE, NOT_READY_LINE)
            if int(match.group(1)) != self.n:
                raise run.CaseError(f"manager reports {match.group(1)} processes ready")
            rec: Record = {"mgr_ready": t_ready - t0}
            with connect(f"127.0.0.1:{port}", timeout=30) as mgr:
                status = mgr.status()
                if sum(s["state"] == "ready" for s in status) != self.n:
                    raise run.CaseError(f"status after 'all ready': "
                                        f"{[s['state'] for s in status]}")
                self.check_running("after all ready")
                rec.update(breakdown(mgr, self.n, wall0, wall0 + rec["mgr_ready"]))
                t = time.monotonic()
                mgr.stop("all")
                rec["mgr_stop"] = time.monotonic() - t
                self.check_gone("after stop('all')")
                t = time.monotonic()
                mgr.start("all")
                mgr.wait_ready("all", timeout=run.LINE_TIMEOUT)
                rec["api_ready"] = time.monotonic() - t
                self.check_running("after start + wait_ready")
                t = time.monotonic()
                mgr.quit()
            code = child.wait()
            rec["mgr_quit"] = time.monotonic() - t
            if code != 0:
                raise run.CaseError(f"manager exited with {code}: {child.tail()}")
            self.check_gone("after quit")
        except (run.CaseError, ManagerError, subprocess.TimeoutExpired, OSError) as exc:
            child.kill()
            left = run.with_token(self.token)
            run.terminate_pids(left)
            raise run.CaseError(f"{exc}") from None
        self.managers.remove(child)
        return rec

    def python(self) -> Record:
        """For scale: the interpreter's start alone, and with the imports of ln_manager -c
        (what cli.main and its _serve load before the first process starts)."""
        rec: Record = {}
        for key, code in (("py_start", "pass"), ("py_imports", IMPORTS)):
            t = time.monotonic()
            done = subprocess.run([sys.executable, "-c", code], env=self.env,
                                  capture_output=True, text=True)
            if done.returncode != 0:
                raise run.CaseError(f"python -c {code!r}: {done.stderr.strip()[-500:]}")
            rec[key] = time.monotonic() - t
        return rec

    def shell(self) -> Record:
        """Launch floor.sh until its "all ready" line; then its kill + wait."""
        work = self.scratch("sh")
        argv = ["/bin/sh", str(HERE / "floor.sh"), str(self.prog), self.token, str(work),
                str(self.n)]
        t0 = time.monotonic()
        child = run.Child(argv, self.env, work / "stderr", stdin=subprocess.PIPE)
        try:
            t_ready, match = child.expect(r"^all (\d+) ready")
            if int(match.group(1)) != self.n:
                raise run.CaseError(f"floor.sh reports {match.group(1)} processes ready")
            rec: Record = {"shell_ready": t_ready - t0}
            self.check_running("floor.sh after all ready")
            t = time.monotonic()
            child.send("stop\n")
            t_stop, _ = child.expect(r"^stopped$")
            rec["shell_stop"] = t_stop - t
            child.wait()
            self.check_gone("floor.sh after stop")
        except (run.CaseError, subprocess.TimeoutExpired, OSError) as exc:
            child.kill()
            run.terminate_pids(run.with_token(self.token))
            raise run.CaseError(f"floor.sh: {exc}") from None
        return rec


def breakdown(mgr: Any, n: int, launched: float, line: float) -> Record:
    """Where the manager's time went, from every process's recorded transitions (wall-clock
    times): launch -> first `starting`, first `starting` -> last `ready`, last `ready` -> the
    "all ready" line; and the medians of the hop from a parent's `ready` to its child's
    `started` and of `started` -> `ready` of one process."""
    first: list[dict[str, float]] = []
    for i in range(n):
        seen: dict[str, float] = {}
        for t in mgr.history(f"p{i}"):
            seen.setdefault(t["state"], t["time"])
        if not {"starting", "started", "ready"} <= seen.keys():
            raise run.CaseError(f"p{i}: history without starting/started/ready: {seen}")
        first.append(seen)
    start = min(s["starting"] for s in first)
    ready = max(s["ready"] for s in first)
    return {"mgr_to_first_start": start - launched, "mgr_tree": ready - start,
            "mgr_report": line - ready,
            "mgr_hop": statistics.median(first[i]["started"] - first[run.parent(i)]["ready"]
                                         for i in range(1, n)) if n > 1 else 0.0}


class Daemon:
    """The warm daemon: started once before the rounds, in the foreground as our child."""

    def __init__(self, tmp: Path) -> None:
        self.port = run.free_port()
        self.key_file = tmp / "warm" / "daemon.key"
        self.key_file.parent.mkdir()
        dk.create_key_file(self.key_file)
        self.log = tmp / "warm" / "ln_daemon.log"
        self.argv = [dl.daemon_executable(), "--port", str(self.port), "--bind", "127.0.0.1",
                     "--key-file", str(self.key_file), "--log", str(self.log), "--foreground"]
        self.proc = subprocess.Popen(self.argv, stdin=subprocess.DEVNULL,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                     start_new_session=True)
        run.wait_listening(self.port, self.proc)

    def stop(self) -> int:
        if self.proc.poll() is None:
            self.proc.terminate()
        try:
            return self.proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            return self.proc.wait()


def attempt(runs: list[Record], kind: str, rnd: int | str, fn: Any, *args: Any) -> None:
    t0 = time.monotonic()
    try:
        rec = fn(*args)
        shown = ", ".join(f"{k} {ms(v)} ms" for k, v in rec.items() if k in MEASURES)
        log(f"  {kind}: {shown} ({time.monotonic() - t0:.1f} s)")
    except run.CaseError as exc:
        log(f"  {kind}: ERROR {exc}")
        rec = {"error": str(exc)}
    runs.append({"round": rnd, "system": kind, **rec})


def summarize(runs: list[Record]) -> dict[str, Record]:
    """Per measurement: median, min and max in seconds over the rounds that had it."""
    out: dict[str, Record] = {}
    for key in MEASURES:
        values = [r[key] for r in runs if key in r]
        if values:
            out[key] = {"median": statistics.median(values), "min": min(values),
                        "max": max(values), "rounds": len(values)}
    return out


def goals(summary: dict[str, Record]) -> list[Record]:
    ready = summary.get("mgr_ready", {}).get("median")
    floor = summary.get("shell_ready", {}).get("median")
    ratio = ready / floor if ready is not None and floor else None
    return [
        {"goal": f"all-ready (warm daemon) <= {GOAL_SECONDS} s", "value": ready,
         "unit": "s", "target": GOAL_SECONDS,
         "result": "n/a" if ready is None else "PASS" if ready <= GOAL_SECONDS else "MISS"},
        {"goal": f"all-ready <= {GOAL_RATIO:g}x the shell floor", "value": ratio, "unit": "x",
         "target": GOAL_RATIO,
         "result": "n/a" if ratio is None else "PASS" if ratio <= GOAL_RATIO else "MISS"},
    ]


def table(summary: dict[str, Record], cold: Record, n: int, rounds: int) -> list[str]:
    out = [f"{n} trivial processes in a binary tree ({run.tree_depth(n)} levels), ms: median, "
           f"min and max over {rounds} rounds",
           f"{'':<38}{'median':>9}{'min':>9}{'max':>9}  note"]
    for key, (label, note) in MEASURES.items():
        rec = summary.get(key)
        if rec is None:
            out.append(f"{label:<38}{'-':>9}{'-':>9}{'-':>9}  {note} (no successful round)")
            continue
        out.append(f"{label:<38}{ms(rec['median']):>9}{ms(rec['min']):>9}{ms(rec['max']):>9}"
                   f"  {note}")
    if "error" in cold:
        out.append(f"{'ln_manager -c: launch -> all ready':<38}  cold: ERROR {cold['error']}")
    else:
        out.append(f"{'ln_manager -c: launch -> all ready':<38}{ms(cold['mgr_ready']):>9}"
                   f"{'':>18}  cold daemon (started by the manager), once; of which "
                   f"{ms(cold['mgr_to_first_start'])} ms to the first start")
    return out


def goals_table(results: list[Record]) -> list[str]:
    out = [f"{'goal':<40}{'value':>10}{'target':>10}  result"]
    for g in results:
        value = "-" if g["value"] is None else f"{g['value']:.3f} s" if g["unit"] == "s" \
            else f"{g['value']:.1f}x"
        target = f"{g['target']:g} s" if g["unit"] == "s" else f"{g['target']:g}x"
        out.append(f"{g['goal']:<40}{value:>10}{target:>10}  {g['result']}")
    return out


def cold_round(bench: Bench, tmp: Path) -> tuple[Record, list[int]]:
    """One manager round with no daemon on its port: the manager starts it (detached) with a
    key file it creates; returns the record and the daemon's pids, to be stopped."""
    port = run.free_port()
    key_file = tmp / "cold" / "daemon.key"
    key_file.parent.mkdir()
    runs: list[Record] = []
    try:
        attempt(runs, "ln_manager (cold)", "cold", bench.manager, port, key_file)
    finally:
        pids = run.daemons_on(port)
    return runs[0], pids


def check_leftovers(bench: Bench, daemon_pids: list[int], tmp: Path) -> list[str]:
    """What the run left behind: processes, daemons, segments, the temporary directory."""
    left = []
    procs = run.with_token(bench.token)
    if procs:
        left.append(f"{len(procs)} ready_proc processes (killed)")
        run.terminate_pids(procs)
    daemons = [p for p in daemon_pids if run.alive(p)]
    if daemons:
        left.append(f"ln_daemon pids {daemons} (killed)")
        run.terminate_pids(daemons)
    segments = run.shm_of(bench.token)
    if segments:
        left.append(f"segments {', '.join(segments)} (removed)")
        for name in segments:
            Path("/dev/shm", name).unlink(missing_ok=True)
    if tmp.exists():
        left.append(f"{tmp} (key files, runtime directory) still exists")
    return left


def main() -> int:
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split()))
    parser.add_argument("--quick", action="store_true",
                        help=f"{QUICK_ROUNDS} rounds: a smoke run, not a measurement")
    parser.add_argument("--rounds", type=int,
                        help=f"rounds (default {ROUNDS}, --quick {QUICK_ROUNDS})")
    parser.add_argument("--processes", type=int, default=PROCESSES,
                        help=f"processes in the tree (default {PROCESSES}; the goals are "
                             f"stated for {PROCESSES})")
    parser.add_argument("--build-dir", type=Path, default=REPO / "build" / "release",
                        help="SCons variant directory with bench/startup/ (build/release)")
    parser.add_argument("--json", type=Path, default=REPO / "bench" / "results" / "startup.json",
                        help="where the results go (bench/results/startup.json)")
    args = parser.parse_args()
    rounds = args.rounds or (QUICK_ROUNDS if args.quick else ROUNDS)
    if args.processes < 1:
        parser.error("--processes must be at least 1")
    prog = args.build_dir / "bench" / "startup" / "ready_proc"
    daemon_exe = dl.daemon_executable()
    missing = [str(p) for p in (prog, Path(daemon_exe)) if not os.access(p, os.X_OK)]
    if missing:
        print(f"bench_startup: {', '.join(missing)} missing: build first with `scons -j2`",
              file=sys.stderr)
        return 2

    load_start = os.getloadavg()
    started = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    runs: list[Record] = []
    warmup: list[Record] = []
    daemon_pids: list[int] = []
    tmp = Path(tempfile.mkdtemp(prefix="ln_bench_startup_"))
    bench = Bench(args, tmp, prog)
    daemon: Daemon | None = None
    try:
        try:
            daemon = Daemon(tmp)
        except (run.CaseError, dw.DaemonError, OSError) as exc:
            print(f"bench_startup: cannot start the warm ln_daemon: {exc}", file=sys.stderr)
            return 1
        daemon_pids.append(daemon.proc.pid)
        log(f"warm ln_daemon pid {daemon.proc.pid} on port {daemon.port}; warm-up round")
        attempt(warmup, "ln_manager", "warm-up", bench.manager, daemon.port, daemon.key_file)
        attempt(warmup, "shell", "warm-up", bench.shell)
        attempt(warmup, "python", "warm-up", bench.python)
        log("cold round: the manager starts its own ln_daemon")
        cold, pids = cold_round(bench, tmp)
        daemon_pids += pids
        run.terminate_pids(pids)
        for rnd in range(rounds):
            log(f"round {rnd + 1}/{rounds}")
            cases = [("ln_manager", bench.manager, daemon.port, daemon.key_file),
                     ("shell", bench.shell), ("python", bench.python)]
            for kind, fn, *fn_args in cases[rnd % 3:] + cases[:rnd % 3]:
                attempt(runs, kind, rnd, fn, *fn_args)
    finally:
        for child in bench.managers:
            child.kill()
        daemon_status = daemon.stop() if daemon is not None else None
        shutil.rmtree(tmp, ignore_errors=True)
        leftover = check_leftovers(bench, daemon_pids, tmp)

    summary = summarize(runs)
    results = goals(summary)
    print(f"goals: {args.processes} processes all ready <= {GOAL_SECONDS} s after launching "
          f"ln_manager, and <= {GOAL_RATIO:g}x the shell floor (medians, warm daemon)")
    print(f"cpu: os.cpu_count()={os.cpu_count()}, usable={len(os.sched_getaffinity(0))}; "
          f"load average at start {load_start[0]:.2f}, at end {os.getloadavg()[0]:.2f}; "
          f"python {platform.python_version()}"
          + ("; --quick: a smoke run, the numbers are not a measurement" if args.quick else ""))
    print("ln_manager: python -m links_and_nodes.manager -c FILE --start-all --wait-ready "
          "--no-console (what the ln_manager script runs); floor: bench/startup/floor.sh")
    for lines in (table(summary, cold, args.processes, rounds), goals_table(results)):
        print()
        print("\n".join(lines))
    failed = [r for r in runs if "error" in r]
    if failed:
        print(f"\n{len(failed)} case(s) failed: " + "; ".join(
            f"round {r['round']} {r['system']}: {r['error']}" for r in failed))
    print("\nleft behind: " + ("; ".join(leftover) if leftover else
                               "nothing (processes, daemons, segments, key files checked)"))

    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({
        "started": started, "quick": args.quick, "machine": platform.machine(),
        "kernel": platform.release(), "python_version": platform.python_version(),
        "cpu_count": os.cpu_count(), "usable_cpus": sorted(os.sched_getaffinity(0)),
        "loadavg_start": load_start, "loadavg_end": os.getloadavg(),
        "processes": args.processes, "tree_levels": run.tree_depth(args.processes),
        "rounds": rounds, "seconds": "every time is in seconds",
        "measures": {k: {"label": v[0].strip(), "note": v[1]} for k, v in MEASURES.items()},
        "warmup": warmup, "cold": cold, "runs": runs, "summary": summary, "goals": results,
        "warm_daemon_exit": daemon_status, "leftover": leftover,
    }, indent=2) + "\n")
    print(f"\nwrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
