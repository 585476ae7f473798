"""Benchmark of the daemon's resource sampling (docs/daemon.md, "Resource samples"; issue 31).
Goal: sampling 200 processes at 1 Hz costs the ln_daemon < 1 % of a core.

Starts its own ln_daemon (build/release/ln_daemon/ln_daemon: run scons first) with N
processes (`sleep`) of one instance, then measures the daemon's CPU time (every thread's
/proc/PID/task/*/schedstat, nanoseconds) over the same wall time in three phases, in this
run: not sampling (the baseline), sampling at 1 Hz, and at 10 Hz (more rounds, for a finer
per-round figure).  The cost of sampling is a phase's CPU share minus the baseline's.
Prints a table with the goal and PASS/MISS, writes bench/results/resources.json and .txt,
exits 0 either way.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(REPO / "python"))

from links_and_nodes.manager.processes import daemon_client as dc  # noqa: E402
from links_and_nodes.manager.processes import daemon_keys as dk  # noqa: E402
from links_and_nodes.manager.processes import daemon_wire as dw  # noqa: E402
from links_and_nodes.manager.processes.daemon_launch import daemon_executable  # noqa: E402
from links_and_nodes.manager.processes.daemon_resources import ResourceSample  # noqa: E402

GOAL_PERCENT = 1.0  # of one core, at 1 Hz with 200 processes
FULL = {"seconds": 30.0}
QUICK = {"seconds": 5.0}


def log(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def cpu_ns(pid: int) -> int:
    """CPU time of every thread of `pid` so far, in ns."""
    total = 0
    for task in Path(f"/proc/{pid}/task").iterdir():
        try:
            total += int((task / "schedstat").read_text().split()[0])
        except (OSError, ValueError, IndexError):
            pass  # a thread that ended meanwhile
    return total


def start_daemon(tmp: Path) -> tuple[subprocess.Popen[str], int]:
    key = tmp / "daemon.key"
    dk.create_key_file(key)
    proc = subprocess.Popen([daemon_executable(), "--foreground", "--port", "0", "--bind",
                             "127.0.0.1", "--data-port", "0", "--key-file", str(key),
                             "--log", str(tmp / "daemon.log")], stdout=subprocess.PIPE,
                            text=True)
    assert proc.stdout is not None
    line = proc.stdout.readline()  # "ln_daemon: listening on 127.0.0.1:PORT (pid N), ..."
    if "listening on" not in line:
        raise SystemExit(f"ln_daemon did not start: {line!r}")
    port = int(line.split("listening on ", 1)[1].split()[0].rsplit(":", 1)[1])
    return proc, port


async def phase(client: dc.DaemonClient, pid: int, period: float | None, seconds: float,
                expect: int) -> dict[str, Any]:
    """The daemon's CPU share over `seconds` while sampling every `period` s (None: not)."""
    queue = client.events()
    while not queue.empty():
        queue.get_nowait()
    if period is not None:
        await client.resources(period)
    t0, c0 = time.monotonic(), cpu_ns(pid)
    samples, short = 0, 0
    end = t0 + seconds
    while (left := end - time.monotonic()) > 0:
        try:
            event = await asyncio.wait_for(queue.get(), left)
        except TimeoutError:
            break
        if isinstance(event, ResourceSample):
            samples += 1
            short += len(event.processes) != expect
    t1, c1 = time.monotonic(), cpu_ns(pid)
    if period is not None:
        await client.resources(-1)
    wall = t1 - t0
    return {"period_s": period, "wall_s": wall, "cpu_s": (c1 - c0) / 1e9,
            "cpu_percent": 100.0 * (c1 - c0) / 1e9 / wall, "samples": samples,
            "samples_missing_processes": short}


async def run(port: int, pid: int, n: int, seconds: float) -> dict[str, Any]:
    key = dk.read_key_file(Path(os.environ["LN_BENCH_KEY"]))
    client = await dc.DaemonClient.connect("127.0.0.1", port, key, "bench-resources")
    try:
        log(f"starting {n} processes")
        for i in range(n):
            await client.spawn(dw.SpawnSpec(name=f"p{i:03d}", command="sleep 3600",
                                            shell=False, argv=["sleep", "3600"],
                                            env={"PATH": "/usr/bin:/bin"}, use_pty=False))
        await asyncio.sleep(1.0)
        phases = {}
        for name, period in (("baseline", None), ("1 Hz", 1.0), ("10 Hz", 0.1)):
            log(f"phase {name}: {seconds:g} s")
            phases[name] = await phase(client, pid, period, seconds, n)
        return phases
    finally:
        await client.close()


def report(phases: dict[str, Any], n: int, quick: bool) -> dict[str, Any]:
    base = phases["baseline"]["cpu_percent"]
    direct = phases["1 Hz"]["cpu_percent"] - base
    fast = phases["10 Hz"]
    round_ms = max(0.0, (fast["cpu_percent"] - base) / 100 * fast["wall_s"]) \
        / max(1, fast["samples"]) * 1000
    derived = round_ms / 1000 * 100  # one round per second, in % of a core
    return {"goal": f"sampling {n} processes at 1 Hz costs the daemon < {GOAL_PERCENT} % of "
                    "a core", "processes": n, "quick": quick, "phases": phases,
            "cost_1hz_percent": direct, "round_ms": round_ms,
            "cost_1hz_from_10hz_percent": derived,
            "pass": direct < GOAL_PERCENT and derived < GOAL_PERCENT}


def table(r: dict[str, Any]) -> str:
    rows = [f"# {r['goal']}" + (" (--quick)" if r["quick"] else ""),
            f"{'phase':10} {'wall s':>7} {'daemon cpu s':>12} {'cpu %':>7} {'samples':>8}"]
    for name, p in r["phases"].items():
        rows.append(f"{name:10} {p['wall_s']:7.2f} {p['cpu_s']:12.4f} {p['cpu_percent']:7.3f} "
                    f"{p['samples']:8d}")
    rows.append(f"cost at 1 Hz (1 Hz - baseline): {r['cost_1hz_percent']:.3f} % of a core")
    rows.append(f"cost per round (10 Hz phase): {r['round_ms']:.3f} ms -> at 1 Hz "
                f"{r['cost_1hz_from_10hz_percent']:.3f} % of a core")
    rows.append(f"goal < {GOAL_PERCENT} %: {'PASS' if r['pass'] else 'MISS'}")
    return "\n".join(rows) + "\n"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="5 s per phase instead of 30 s")
    ap.add_argument("--processes", type=int, default=200, help="processes sampled (200)")
    ap.add_argument("--out", type=Path, default=REPO / "bench" / "results" / "resources.json",
                    help="where the results go (the table beside it as .txt)")
    args = ap.parse_args()
    seconds = (QUICK if args.quick else FULL)["seconds"]
    with tempfile.TemporaryDirectory(prefix="ln_bench_resources_") as tmp:
        proc, port = start_daemon(Path(tmp))
        os.environ["LN_BENCH_KEY"] = str(Path(tmp) / "daemon.key")
        try:
            phases = asyncio.run(run(port, proc.pid, args.processes, seconds))
        finally:
            proc.send_signal(signal.SIGTERM)  # stops every process it runs, then ends
            try:
                proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                proc.kill()
    r = report(phases, args.processes, args.quick)
    text = table(r)
    print(text, end="")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(r, indent=2) + "\n")
    args.out.with_suffix(".txt").write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
