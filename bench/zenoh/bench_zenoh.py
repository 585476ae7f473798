"""Benchmark of ln_zenoh: one-way latency (ping-pong / 2, p50/p99) and one-way throughput of
64 B and 1 MiB samples between lab hosts a and b (network namespaces on a bridge,
tests/python/netlab.py), for

    bridge     ln topics at site a -> ln_zenoh (a) -> Zenoh TCP -> ln_zenoh (b) -> ln topics at b,
               topic samples through the bridges' native core (--native on)
    bridge_py  the same with the samples through Python (--native off): the bridge before
               its native core, measured in the same run
    bridge_1by1  the native core with --batch off: one Zenoh message per sample, the bridge
               before batches between bridges (docs/zenoh.md), measured in the same run
    zenoh      plain Zenoh pub/sub between two Python processes on a and b (the floor)
    daemons  the same ln programs with one manager, the ln_daemons forwarding over UDP

All measuring programs are Python (zb_bench_peer.py), so the three differ only in the path.
Goal: the bridge adds at most 1.3x over plain Zenoh (p50 latency; throughput at least 1/1.3).
Prints a table, writes bench/results/zenoh.json, exits 0 either way.  Needs root and zenoh.

    sudo .venv/bin/python bench/zenoh/bench_zenoh.py [--quick] [--only 64:throughput]
        [--systems zenoh,bridge,bridge_1by1]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
import uuid
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
for _p in (REPO / "tests" / "python", HERE.parent / "network", REPO, REPO / "python"):
    sys.path.insert(0, str(_p))

from netlab import Host, NetLab, netlab_available  # noqa: E402
from network_cases import CaseError, Lab, Proc, json_line  # noqa: E402

PEER = HERE / "zb_bench_peer.py"
MIB = 1 << 20
SIZES = (64, MIB)
LAT = {64: (2000, 200), MIB: (200, 20)}  # round trips, warm-up
THR = {64: 100000, MIB: 1000}  # samples of a throughput run: long enough for a steady state
ROUNDS = 3  # each case runs this often, the systems in turn; the median round is reported
GOAL = 1.3
SITE_PORT = 54500  # the bridge case's managers (one per host)
ZENOH_PORT = 7447
PLAIN_PORT = 7450
SYSTEMS = ("zenoh", "bridge", "bridge_py", "daemons", "bridge_1by1")
# the bridge pairs: topic-name prefix, key prefixes of site a's and b's bridge, Zenoh port,
# --native, --batch
PAIRS = {"bridge": ("b", "ln/a", "ln/b", ZENOH_PORT, "on", "on"),
         "bridge_py": ("p", "ln/pa", "ln/pb", ZENOH_PORT + 1, "off", "off"),
         "bridge_1by1": ("n", "ln/na", "ln/nb", ZENOH_PORT + 2, "on", "off")}
TIMEOUT = 600.0


def log(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def env(host: Host, manager: str | None = None) -> dict[str, str]:
    e = {**host.env(), "PYTHONPATH": os.pathsep.join([str(REPO / "python"), str(REPO)]),
         "LN_MESSAGE_DEFINITION_DIRS": str(REPO / "bench" / "md"), "PYTHONUNBUFFERED": "1"}
    if manager:
        e["LN_MANAGER"] = manager
    return e


def wait_line(path: Path, text: str, proc: subprocess.Popen[Any]) -> None:
    deadline = time.monotonic() + 60
    while text not in (path.read_text(errors="replace") if path.exists() else ""):
        if proc.poll() is not None or time.monotonic() > deadline:
            raise CaseError(f"{path.name}: no {text!r}: {path.read_text()[-500:]}")
        time.sleep(0.02)


class Bench:
    def __init__(self, nl: NetLab, quick: bool) -> None:
        self.nl = nl
        self.lab = Lab(nl, REPO / "build" / "release" / "bench" / "network")
        self.a, self.b = self.lab.a, self.lab.b
        self.scale = 10 if quick else 1
        self.procs: list[subprocess.Popen[Any]] = []
        self._managers_up = False
        self._pairs_up: set[str] = set()

    def close(self) -> None:
        for proc in self.procs:
            if proc.poll() is None:
                proc.terminate()
        for proc in self.procs:
            try:
                proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                proc.kill()

    def spawn(self, host: Host, argv: list[str], log_name: str,
              manager: str | None = None) -> subprocess.Popen[Any]:
        proc = host.popen(argv, env=env(host, manager), log=log_name)
        self.procs.append(proc)
        return proc

    def peer(self, host: Host, args: list[str], log_name: str,
             manager: str | None = None) -> subprocess.Popen[Any]:
        return self.spawn(host, [sys.executable, str(PEER), *args], log_name, manager)

    def finish(self, proc: subprocess.Popen[Any], what: str) -> dict[str, Any]:
        try:
            proc.wait(timeout=TIMEOUT)
        except subprocess.TimeoutExpired:
            proc.kill()
            raise CaseError(f"{what}: no result in {TIMEOUT:.0f} s") from None
        assert proc.log_path is not None  # type: ignore[attr-defined]
        return json_line(proc.log_path.read_text(errors="replace"), what)  # type: ignore

    # ---- the bridge ----------------------------------------------------------------------------
    def bridges(self, system: str) -> None:
        """The site managers (once) and the bridge pair of `system`."""
        if not self._managers_up:
            for host, name in ((self.a, "a"), (self.b, "b")):
                mgr = self.spawn(host, [sys.executable, "-m", "links_and_nodes.manager",
                                        "--port", str(SITE_PORT), "--instance",
                                        f"zbench{name}{uuid.uuid4().hex[:6]}", "--no-console",
                                        "--log-level", "warning"], f"site-{name}.manager.log")
                wait_line(mgr.log_path, "listening on", mgr)  # type: ignore[attr-defined]
            self._managers_up = True
        if system in self._pairs_up:
            return
        tag, prefix_a, prefix_b, port, native, batch = PAIRS[system]
        manager = f"127.0.0.1:{SITE_PORT}"
        names = [f"{tag}{size}" for size in SIZES]
        # queued depth of the data topics: 1024 samples of 64 B, 32 of 1 MiB (ring memory)
        data = {f"{tag}{size}": f"{tag}{size}.data,queued={1024 if size == 64 else 32}"
                for size in SIZES}
        out_a = [x for n in names for x in ("--out", f"{n}.ping", "--out", data[n])]
        in_a = [x for n in names for x in ("--in", f"{n}.pong")]
        out_b = [x for n in names for x in ("--out", f"{n}.pong")]
        in_b = [x for n in names for x in ("--in", f"{n}.ping", "--in", data[n])]
        cli = [sys.executable, "-m", "links_and_nodes.zenoh_bridge.cli", "--poll", "0.2",
               "--native", native, "--batch", batch]
        endpoint = f"tcp/{self.a.address}:{port}"
        bridge_a = self.spawn(self.a, [*cli, "--prefix", prefix_a, "--remote", prefix_b,
                                       "--listen", endpoint, *out_a, *in_a],
                              f"{system}-a.log", manager)
        bridge_b = self.spawn(self.b, [*cli, "--prefix", prefix_b, "--remote", prefix_a,
                                       "--connect", endpoint, *out_b, *in_b],
                              f"{system}-b.log", manager)
        for proc in (bridge_a, bridge_b):
            wait_line(proc.log_path, "remote bridge", proc)  # type: ignore[attr-defined]
        self._pairs_up.add(system)

    # ---- cases ---------------------------------------------------------------------------------
    def latency(self, size: int, system: str) -> dict[str, Any]:
        count, warmup = (n // self.scale for n in LAT[size])
        tail = [str(size), str(count), str(warmup)]
        if system == "daemons":
            got = self.lab.managed(self.lab.mgr, [
                Proc("pong", "b", self._managed_argv(["ln-pong", str(size), "--transport",
                                                      "udp"]), ready=True),
                Proc("ping", "a", self._managed_argv(["ln-ping", *tail, "--transport", "udp"]))],
                ["ping"], system)
            return got["ping"]
        if system == "zenoh":
            endpoint = f"tcp/{self.b.address}:{PLAIN_PORT}"
            pong = self.peer(self.b, ["z-pong", str(size), "--listen", endpoint,
                                      "--name", f"z{size}"], f"zpong{size}.log")
            wait_line(pong.log_path, "ready", pong)  # type: ignore[attr-defined]
            ping = self.peer(self.a, ["z-ping", *tail, "--connect", endpoint,
                                      "--name", f"z{size}"], f"zping{size}.log")
            result = self.finish(ping, system)
            pong.terminate()
            return result
        self.bridges(system)
        manager = f"127.0.0.1:{SITE_PORT}"
        name = f"{PAIRS[system][0]}{size}"
        pong = self.peer(self.b, ["ln-pong", str(size), "--name", name],
                         f"{name}pong.log", manager)
        wait_line(pong.log_path, "ready", pong)  # type: ignore[attr-defined]
        ping = self.peer(self.a, ["ln-ping", *tail, "--name", name], f"{name}ping.log",
                         manager)
        result = self.finish(ping, system)
        pong.terminate()
        return result

    def throughput(self, size: int, system: str) -> dict[str, Any]:
        count = str(THR[size] // self.scale)
        if system == "daemons":
            got = self.lab.managed(self.lab.mgr, [
                Proc("sink", "b", self._managed_argv(["ln-sink", str(size), count,
                                                      "--transport", "udp"]), ready=True),
                Proc("source", "a", self._managed_argv(["ln-source", str(size), count]))],
                ["sink"], system)
            return got["sink"]
        if system == "zenoh":
            endpoint = f"tcp/{self.b.address}:{PLAIN_PORT + 1}"
            sink = self.peer(self.b, ["z-sink", str(size), count, "--listen", endpoint,
                                      "--name", f"z{size}"], f"zsink{size}.log")
            wait_line(sink.log_path, "ready", sink)  # type: ignore[attr-defined]
            self.peer(self.a, ["z-source", str(size), count, "--connect", endpoint,
                               "--name", f"z{size}"], f"zsource{size}.log")
            return self.finish(sink, system)
        self.bridges(system)
        manager = f"127.0.0.1:{SITE_PORT}"
        name = f"{PAIRS[system][0]}{size}"
        sink = self.peer(self.b, ["ln-sink", str(size), count, "--name", name],
                         f"{name}sink.log", manager)
        wait_line(sink.log_path, "ready", sink)  # type: ignore[attr-defined]
        self.peer(self.a, ["ln-source", str(size), count, "--wait", "--name", name],
                  f"{name}source.log", manager)
        return self.finish(sink, system)

    @staticmethod
    def _managed_argv(args: list[str]) -> list[str]:
        return ["env", f"PYTHONPATH={REPO / 'python'}:{REPO}",
                f"LN_MESSAGE_DEFINITION_DIRS={REPO / 'bench' / 'md'}", sys.executable,
                str(PEER), *args]


def median_run(runs: list[dict[str, Any]], key: str) -> dict[str, Any]:
    """The run whose `key` is the median of the runs (the lower middle one of an even
    count)."""
    ordered = sorted(runs, key=lambda r: r.get(key) or 0.0)
    return dict(ordered[(len(ordered) - 1) // 2])


def table(results: dict[str, Any]) -> list[str]:
    lines = ["", f"{'case':<28}" + "".join(f"{s:>12}" for s in SYSTEMS)
             + f"{'bridge/zenoh':>14}"]
    verdicts = []
    for size in SIZES:
        label = "64 B" if size == 64 else "1 MiB"
        lat = results["latency"].get(str(size), {})
        for q in ("p50_us", "p99_us") if lat else ():
            vals = [lat.get(s, {}).get(q) for s in SYSTEMS]
            ratio = vals[1] / vals[0] if vals[0] and vals[1] else None
            lines.append(f"{label + ' one-way ' + q[:3] + ' (µs)':<28}"
                         + "".join(f"{v:>12.1f}" if v else f"{'-':>12}" for v in vals)
                         + (f"{ratio:>13.2f}x" if ratio else f"{'-':>14}"))
            if q == "p50_us" and ratio:
                verdicts.append((f"{label} p50 latency bridge/zenoh {ratio:.2f}x <= {GOAL}x",
                                 ratio <= GOAL))
        thr = results["throughput"].get(str(size), {})
        if not thr:
            continue
        vals = [thr.get(s, {}).get("msgs_per_s") for s in SYSTEMS]
        got = [thr.get(s, {}).get("received") for s in SYSTEMS]
        sent = thr.get("zenoh", {}).get("sent")
        ratio = vals[0] / vals[1] if vals[0] and vals[1] else None
        lines.append(f"{label + ' msgs/s':<28}" + "".join(f"{v:>12.0f}" if v else f"{'-':>12}"
                                                          for v in vals)
                     + (f"{1 / ratio:>13.2f}x" if ratio else f"{'-':>14}"))
        lines.append(f"{label + ' received of ' + str(sent):<28}"
                     + "".join(f"{g:>12}" if g is not None else f"{'-':>12}" for g in got))
        if ratio:
            verdicts.append((f"{label} throughput zenoh/bridge {ratio:.2f}x <= {GOAL}x",
                             ratio <= GOAL))
    lines.append("")
    lines += [f"{'PASS' if ok else 'MISS'}  {text}" for text, ok in verdicts]
    return lines


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="a tenth of the samples")
    ap.add_argument("--only", metavar="SIZE:KIND", action="append", default=[],
                    help="only these cases, e.g. 64:throughput or 1048576:latency (repeatable)")
    ap.add_argument("--systems", default=",".join(SYSTEMS),
                    help=f"comma-separated systems to measure (default {','.join(SYSTEMS)})")
    ap.add_argument("--out", default=str(REPO / "bench" / "results" / "zenoh.json"),
                    help="the JSON file (the table goes beside it as .txt)")
    args = ap.parse_args()
    systems = tuple(s for s in SYSTEMS if s in args.systems.split(","))
    why = netlab_available()
    if why:
        log(f"bench_zenoh: cannot build the lab: {why}")
        return 0
    try:
        import zenoh  # noqa: F401
    except ImportError:
        log("bench_zenoh: the Python package zenoh is missing: pip install eclipse-zenoh")
        return 0
    results: dict[str, Any] = {"latency": {}, "throughput": {}, "errors": []}
    with tempfile.TemporaryDirectory(prefix="bench_zenoh.") as tmp, NetLab(Path(tmp)) as nl:
        bench = Bench(nl, args.quick)
        rounds = 1 if args.quick else ROUNDS
        try:
            for size in SIZES:
                for kind in ("latency", "throughput"):
                    if args.only and f"{size}:{kind}" not in args.only:
                        continue
                    runs: dict[str, list[dict[str, Any]]] = {s: [] for s in systems}
                    for r in range(rounds):
                        # the systems in turn, starting with another one each round
                        for system in systems[r % len(systems):] + systems[:r % len(systems)]:
                            log(f"{kind} {size} B {system} (round {r + 1}/{rounds}) ...")
                            try:
                                runs[system].append(getattr(bench, kind)(size, system))
                            except CaseError as exc:
                                results["errors"].append(str(exc))
                                log(f"  failed: {exc}")
                    key = "p50_us" if kind == "latency" else "msgs_per_s"
                    results[kind][str(size)] = {
                        system: {**median_run(got, key), "rounds": got}
                        for system, got in runs.items() if got}
        finally:
            bench.close()
    results.update(machine=platform.machine(), cpus=os.cpu_count(), quick=args.quick,
                   only=args.only, systems=list(systems),
                   goal=f"bridge <= {GOAL}x plain Zenoh", python=platform.python_version())
    lines = table(results)
    print("\n".join(lines))
    out = Path(args.out).resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(results, indent=1))
    out.with_suffix(".txt").write_text("\n".join(lines) + "\n")
    print(f"\n{os.cpu_count()} CPUs; results in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
