"""Benchmark of the manager's web UI (docs/webui.md): the manager's CPU use while a headless
Chromium shows a scope of 8 signals of a 1 kHz topic (arm.state position[0..6] and
velocity[0] of the demo robot), and the latency from publish to the page receiving a sample
(publish time, CLOCK_REALTIME, against the page's performance.timeOrigin + now() on the
same host clock), side by side with the console's `topic echo --json` path (the same
manager, its stdout read here) and the manager idle.  Runs examples/robot/robot.lnc with
its own instance, ports, daemon and runtime directory (builds nothing: run scons first),
prints a table with the goals and PASS/MISS, writes bench/results/webui.json, exits 0
either way."""

from __future__ import annotations

import argparse
import json
import os
import selectors
import socket
import subprocess
import sys
import tempfile
import time
import uuid
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
CONFIG = REPO / "examples" / "robot" / "robot.lnc"
FIELDS = [f"position[{i}]" for i in range(7)] + ["velocity[0]"]
GOAL_CPU = 25.0  # % of one core
GOAL_P50 = 33.0  # ms: one frame at 30 frames/s
TICK = os.sysconf("SC_CLK_TCK")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def cpu_seconds(pid: int) -> float:
    """utime + stime of every thread of `pid` (/proc/PID/stat fields 14 and 15)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


def percentiles(values: list[float]) -> dict[str, float | None]:
    if not values:
        return {"n": 0, "p50": None, "p99": None, "max": None}
    values = sorted(values)
    return {"n": len(values), "p50": values[len(values) // 2],
            "p99": values[min(len(values) - 1, int(len(values) * 0.99))], "max": values[-1]}


class Manager:
    """robot.lnc under ln_manager --webui with a console on a pipe."""

    def __init__(self, tmp: Path) -> None:
        self.port = free_port()
        env = {**os.environ, "LN_RUNTIME_DIR": str(tmp / "run"),
               "LN_DAEMON_KEY_FILE": str(tmp / "key" / "daemon.key"),
               "LN_ARBITER_PORT": str(free_port()), "LN_DEMO_PORT": str(self.port),
               "LN_PYTHON": sys.executable}
        env.pop("LN_MANAGER", None)
        env.pop("LNM_WEBUI_AUTH_FILE", None)
        self.log = open(tmp / "manager.log", "w")  # noqa: SIM115 - closed in stop()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "links_and_nodes.manager", "-c", str(CONFIG), "--instance",
             f"webui_bench_{uuid.uuid4().hex[:8]}", "--start-all", "--wait-ready",
             "--ready-timeout", "60", "--exit-on-failure", "--webui"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self.log, env=env)
        assert self.proc.stdout is not None
        os.set_blocking(self.proc.stdout.fileno(), False)
        self.buffer = b""
        self.url = ""
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline:
            for line in self.lines(0.2):
                if line.startswith("ln_manager: web UI on "):
                    self.url = line.rsplit(" ", 1)[1]
                if "all 3 processes ready" in line:
                    return
            if self.proc.poll() is not None:
                break
        raise RuntimeError(f"the demo did not get ready: see {tmp / 'manager.log'}")

    def lines(self, wait: float) -> list[str]:
        """Complete stdout lines that came within `wait` seconds."""
        assert self.proc.stdout is not None
        sel = selectors.DefaultSelector()
        sel.register(self.proc.stdout, selectors.EVENT_READ)
        if sel.select(wait):
            self.buffer += self.proc.stdout.read() or b""
        sel.close()
        *done, self.buffer = self.buffer.split(b"\n")
        return [x.decode(errors="replace") for x in done]

    def type(self, line: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(line.encode() + b"\n")
        self.proc.stdin.flush()

    def stop(self) -> None:
        try:
            self.type("quit")
            self.proc.wait(timeout=60)
        except (OSError, subprocess.TimeoutExpired):
            self.proc.kill()
            self.proc.wait()
        self.log.close()


def idle(mgr: Manager, seconds: float) -> dict[str, Any]:
    before = cpu_seconds(mgr.proc.pid)
    time.sleep(seconds)
    return {"cpu_percent": 100 * (cpu_seconds(mgr.proc.pid) - before) / seconds}


def browser(mgr: Manager, seconds: float) -> dict[str, Any]:
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--window-size=1400,900"):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
    try:
        driver.get(mgr.url + "#scope")
        deadline = time.monotonic() + 60
        while not driver.execute_script("return window.lnm && window.lnm.ready"):
            if time.monotonic() > deadline:
                raise RuntimeError("the page did not get ready")
            time.sleep(0.1)
        driver.execute_script(f"lnm.scope.add('arm.state', {json.dumps(FIELDS)})")
        time.sleep(2.0)  # warm up: subscriptions, first frames
        driver.execute_script("lnm.scope.latency = []")
        start = driver.execute_script("return [lnm.scope.frames, lnm.scope.received]")
        cpu0 = cpu_seconds(mgr.proc.pid)
        time.sleep(seconds)
        cpu1 = cpu_seconds(mgr.proc.pid)
        end = driver.execute_script("return [lnm.scope.frames, lnm.scope.received]")
        latency = driver.execute_script("return lnm.scope.latency")
        points = driver.execute_script("return lnm.scope.buffers()[0].t.length")
    finally:
        driver.quit()
    return {"cpu_percent": 100 * (cpu1 - cpu0) / seconds,
            "frames_per_s": (end[0] - start[0]) / seconds,
            "samples_per_s": (end[1] - start[1]) / seconds, "signals": len(FIELDS),
            "points_per_signal": points, "latency_ms": percentiles(latency)}


def console_echo(mgr: Manager, seconds: float) -> dict[str, Any]:
    mgr.type("topic echo arm.state --json")
    end = time.monotonic() + 2.0  # warm up
    while time.monotonic() < end:
        mgr.lines(0.1)
    latency: list[float] = []
    count = 0
    cpu0 = cpu_seconds(mgr.proc.pid)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        lines = mgr.lines(0.05)
        now = time.time_ns()
        for line in lines:
            if line.startswith("{") and "publish_time_ns" in line:
                latency.append((now - json.loads(line)["publish_time_ns"]) / 1e6)
                count += 1
    cpu1 = cpu_seconds(mgr.proc.pid)
    mgr.type("status")  # the next command ends the echo
    time.sleep(0.5)
    mgr.lines(0.1)
    return {"cpu_percent": 100 * (cpu1 - cpu0) / seconds, "samples_per_s": count / seconds,
            "latency_ms": percentiles(latency)}


def fmt(value: float | None, digits: int = 1) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def main() -> int:
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split()))
    parser.add_argument("--quick", action="store_true",
                        help="3 s per measurement instead of 15: a smoke run")
    parser.add_argument("--json", type=Path, default=REPO / "bench" / "results" / "webui.json",
                        help="where the results go (bench/results/webui.json)")
    args = parser.parse_args()
    seconds = 3.0 if args.quick else 15.0
    for exe in ("arm_sensor", "arm_controller"):
        if not (REPO / "build" / "release" / "examples" / "robot" / exe).exists():
            print(f"bench_webui: examples/robot/{exe} is not built: run scons -j2 first",
                  file=sys.stderr)
            return 2
    started = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    load_start = os.getloadavg()[0]
    with tempfile.TemporaryDirectory(prefix="ln_bench_webui_") as tmp:
        mgr = Manager(Path(tmp))
        try:
            results = {"idle": idle(mgr, seconds), "webui_scope": browser(mgr, seconds),
                       "console_echo": console_echo(mgr, seconds)}
        finally:
            mgr.stop()
    ui = results["webui_scope"]
    cpu_ok = ui["cpu_percent"] < GOAL_CPU
    p50 = ui["latency_ms"]["p50"]
    lat_ok = p50 is not None and p50 < GOAL_P50
    print(f"goal: manager < {GOAL_CPU:.0f} % of one core with the web UI's scope of "
          f"{len(FIELDS)} signals at 1 kHz; publish -> browser p50 < {GOAL_P50:.0f} ms")
    print(f"cpu: os.cpu_count()={os.cpu_count()}, usable={len(os.sched_getaffinity(0))}; "
          f"load average at start {load_start:.2f}, at end {os.getloadavg()[0]:.2f}; "
          f"{seconds:g} s per measurement" + ("; --quick: a smoke run" if args.quick else ""))
    print()
    print("| path | manager CPU % of a core | samples/s delivered | latency p50 ms | "
          "p99 ms | max ms | frames/s |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    print(f"| manager idle (demo running) | {fmt(results['idle']['cpu_percent'])} | - | - | "
          f"- | - | - |")
    for name, r in (("web UI scope, 8 signals (Chromium)", ui),
                    ("console `topic echo --json` (stdout)", results["console_echo"])):
        lat = r["latency_ms"]
        print(f"| {name} | {fmt(r['cpu_percent'])} | {fmt(r['samples_per_s'], 0)} | "
              f"{fmt(lat['p50'])} | {fmt(lat['p99'])} | {fmt(lat['max'])} | "
              f"{fmt(r.get('frames_per_s'), 0) if 'frames_per_s' in r else '-'} |")
    print()
    print(f"manager CPU with the scope: {fmt(ui['cpu_percent'])} % "
          f"{'PASS' if cpu_ok else 'MISS'}; p50 {fmt(p50)} ms {'PASS' if lat_ok else 'MISS'}")
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({
        "benchmark": "webui", "started": started, "quick": args.quick, "seconds": seconds,
        "goals": {"cpu_percent": GOAL_CPU, "p50_ms": GOAL_P50},
        "pass": {"cpu": cpu_ok, "p50": lat_ok}, "cpu_count": os.cpu_count(),
        "load_average_start": load_start, "results": results}, indent=2) + "\n")
    print(f"results: {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
