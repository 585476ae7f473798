"""Benchmark of the graph (docs/webui.md, "Graph"; docs/introspection.md, "graph"): a
manager with 200 clients and 1,000 topics (bench/graph/graph_load.py: each client publishes
5 topics at 1 Hz and reads 5 of another's), its web UI's graph page in a headless Chromium.

Goal (issue: a live graph of the running system): the graph of 200 processes and 1,000
topics laid out and drawn in < 1 s in headless Chromium, and its rates updated once a
second with the manager under 10 % of a core.  Measured: the layout and drawing time of the
page (dagre, then the SVG), the time from showing the view to the drawn graph (the `graph`
answer included), the time of one `graph` answer at the manager, and the manager's CPU
(/proc/PID/stat) while the page asks once a second, against the same manager with the same
load and no page (the baseline, measured in the same run).  Prints a table with PASS/MISS,
writes bench/results/graph.json and graph.md; exits 0 either way."""

from __future__ import annotations

import argparse
import json
import os
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
GOAL_DRAW_MS = 1000.0
GOAL_CPU = 10.0  # % of one core
TICK = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid: int) -> float:
    """utime + stime of every thread of `pid` (/proc/PID/stat fields 14 and 15)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


def cpu_percent(pid: int, seconds: float) -> float:
    before = cpu_seconds(pid)
    time.sleep(seconds)
    return 100 * (cpu_seconds(pid) - before) / seconds


def wait(predicate: Any, what: str, limit: float = 120.0) -> Any:
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(0.05)
    raise RuntimeError(f"{what}: not within {limit} s")


def graph_answer(address: str, repeats: int) -> tuple[float, int]:
    """The median time of one `graph` answer (window 0), asked over the client protocol,
    and the size of its JSON."""
    from links_and_nodes.tools.scripting import connect

    times = []
    with connect(address, timeout=60) as mgr:
        for _ in range(repeats):
            t0 = time.perf_counter()
            answer = mgr.command("graph", window=0)
            times.append((time.perf_counter() - t0) * 1000)
            time.sleep(0.2)
    return sorted(times)[len(times) // 2], len(json.dumps(answer))


def page(url: str, nodes: int, seconds: float, pid: int) -> dict[str, Any]:
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--window-size=1400,900"):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
    try:
        driver.get(url)
        wait(lambda: driver.execute_script("return window.lnm && window.lnm.ready"), "the page")
        t0 = time.perf_counter()
        driver.execute_script("lnm.show('graph')")
        timing = wait(lambda: driver.execute_script(
            "const t = lnm.views.graph.timing; return t && t.nodes >= arguments[0] && t",
            nodes), "the graph laid out")
        shown_ms = (time.perf_counter() - t0) * 1000
        time.sleep(2.0)  # the next looks: rates, no new layout
        looks0 = driver.execute_script("return lnm.views.graph.looks")
        layouts0 = driver.execute_script("return lnm.views.graph.layouts")
        cpu = cpu_percent(pid, seconds)
        looks = driver.execute_script("return lnm.views.graph.looks") - looks0
        layouts = driver.execute_script("return lnm.views.graph.layouts") - layouts0
    finally:
        driver.quit()
    return {"layout_ms": timing["layout_ms"], "draw_ms": timing["draw_ms"],
            "laid_out_ms": timing["layout_ms"] + timing["draw_ms"],
            "show_to_drawn_ms": shown_ms, "nodes": timing["nodes"], "edges": timing["edges"],
            "cpu_percent": cpu, "looks_per_s": looks / seconds, "new_layouts": layouts}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Manager:
    """`ln_manager -c` of a configuration with one process that is never started (the web
    UI wants a configuration); the load's clients are clients it did not start."""

    def __init__(self, tmp: Path) -> None:
        port = free_port()
        self.address = f"127.0.0.1:{port}"
        config = tmp / "graph_bench.lnc"
        config.write_text(f"instance\nname: graph_bench_{uuid.uuid4().hex[:8]}\n"
                          f"manager: {self.address}\n\nprocess idle\ncommand: sleep 3600\n")
        self.env = {**os.environ, "LN_RUNTIME_DIR": str(tmp / "run"),
                    "LN_DAEMON_KEY_FILE": str(tmp / "key" / "daemon.key"),
                    "LN_ARBITER_PORT": str(free_port()), "LN_MANAGER": self.address}
        self.log = open(tmp / "manager.log", "w")  # noqa: SIM115 - closed in stop()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "links_and_nodes.manager", "-c", str(config),
             "--no-console", "--webui"], stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
            stderr=self.log, text=True, env=self.env)
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        if "listening on" not in line:
            raise RuntimeError(f"the manager did not start: {line!r}")

    def stop(self) -> None:
        self.proc.terminate()
        try:
            self.proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        assert self.proc.stdout is not None
        self.proc.stdout.close()
        self.log.close()


def run(args: argparse.Namespace, tmp: Path) -> dict[str, Any]:
    mgr = Manager(tmp)
    load = None
    try:
        load = subprocess.Popen([sys.executable, str(HERE / "graph_load.py"), mgr.address,
                                 str(args.clients), str(args.per_client)],
                                stdout=subprocess.PIPE, text=True, env=mgr.env)
        assert load.stdout is not None
        if load.stdout.readline().strip() != "ready":
            raise RuntimeError("graph_load.py did not start")
        time.sleep(2.0)  # settle
        baseline = cpu_percent(mgr.proc.pid, args.seconds)
        answer_ms, answer_bytes = graph_answer(mgr.address, 5 if args.quick else 15)
        nodes = 1 + args.clients + args.clients * args.per_client  # with the idle process
        ui = page(f"http://{mgr.address}/", nodes, args.seconds, mgr.proc.pid)
    finally:
        if load is not None:
            load.kill()
            load.wait()
            assert load.stdout is not None
            load.stdout.close()
        mgr.stop()
    return {"baseline_cpu_percent": baseline, "graph_answer_ms": answer_ms,
            "graph_answer_bytes": answer_bytes, "page": ui}


def main() -> int:
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split()))
    parser.add_argument("--quick", action="store_true",
                        help="4 s per CPU measurement instead of 20: a smoke run")
    parser.add_argument("--clients", type=int, default=200)
    parser.add_argument("--per-client", type=int, default=5, help="topics per client")
    parser.add_argument("--out", type=Path, default=REPO / "bench" / "results" / "graph",
                        help="results: OUT.json and OUT.md (bench/results/graph)")
    args = parser.parse_args()
    args.seconds = 4.0 if args.quick else 20.0
    started = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    load_start = os.getloadavg()[0]
    with tempfile.TemporaryDirectory(prefix="ln_bench_graph_") as tmp:
        r = run(args, Path(tmp))
    ui = r["page"]
    draw_ok = ui["laid_out_ms"] < GOAL_DRAW_MS
    cpu_ok = ui["cpu_percent"] < GOAL_CPU
    lines = [
        f"goal: the graph of {args.clients} processes and {args.clients * args.per_client} "
        f"topics laid out and drawn in < {GOAL_DRAW_MS:.0f} ms in headless Chromium; rates "
        f"updated at 1 Hz with the manager < {GOAL_CPU:.0f} % of a core",
        f"cpu: {os.cpu_count()} cores; load average at start {load_start:.2f}, at end "
        f"{os.getloadavg()[0]:.2f}; {args.seconds:g} s per CPU measurement"
        + ("; --quick: a smoke run" if args.quick else ""), "",
        "| measurement | value |", "| --- | ---: |",
        f"| nodes, edges drawn | {ui['nodes']}, {ui['edges']} |",
        f"| page: dagre layout | {ui['layout_ms']:.0f} ms |",
        f"| page: SVG drawing | {ui['draw_ms']:.0f} ms |",
        f"| page: laid out and drawn | {ui['laid_out_ms']:.0f} ms |",
        f"| page: view shown -> drawn (answer included) | {ui['show_to_drawn_ms']:.0f} ms |",
        f"| manager: one `graph` answer (median; its JSON) | {r['graph_answer_ms']:.1f} ms "
        f"({r['graph_answer_bytes'] / 1000:.0f} KB) |",
        f"| manager CPU, same load, no page (baseline) | {r['baseline_cpu_percent']:.1f} % |",
        f"| manager CPU, graph page open ({ui['looks_per_s']:.2f} looks/s) | "
        f"{ui['cpu_percent']:.1f} % |",
        f"| new layouts while only rates changed | {ui['new_layouts']} |", "",
        f"laid out and drawn: {ui['laid_out_ms']:.0f} ms {'PASS' if draw_ok else 'MISS'}; "
        f"manager CPU: {ui['cpu_percent']:.1f} % {'PASS' if cpu_ok else 'MISS'}"]
    print("\n".join(lines))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.with_suffix(".md").write_text("\n".join(lines) + "\n")
    args.out.with_suffix(".json").write_text(json.dumps({
        "benchmark": "graph", "started": started, "quick": args.quick,
        "seconds": args.seconds, "clients": args.clients,
        "topics": args.clients * args.per_client,
        "goals": {"laid_out_ms": GOAL_DRAW_MS, "cpu_percent": GOAL_CPU},
        "pass": {"laid_out": draw_ok, "cpu": cpu_ok}, "cpu_count": os.cpu_count(),
        "load_average_start": load_start, "results": r}, indent=2) + "\n")
    print(f"results: {args.out}.json, {args.out}.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
