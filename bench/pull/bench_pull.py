"""Benchmark of pull topics (docs/pull.md) against push: a publisher on host a, consumers on
host b, ln_relay in b between them with seeded loss and delay per direction.  For loss
{0, 5, 20 %} x one-way delay {1, 10 ms} x period {2, 20 ms} it runs, at the same time
against the same publisher:

  push      the daemons' UDP forwarding (b's data port behind the relay)
  poll      fixed-rate polling of /sync every period (libln_pull, poll_ms = P)
  naive     DIT as the seed defines it (k = 1, t in [10 ms, 2 s], every timeout re-syncs)
  k1..k3    hardened DIT (ln_pull_options_hardened, t_max = 100 ms) with window k = 1, 2, 3:
            the slots kept beyond ceil(SRTT/P^) (AUTO_WINDOW); k3 is the default

and reports delivered ratio, age of information mean/p99 (1 kHz), packets/s and the RTT of
Interests for already-produced samples.  Builds nothing (run scons first); needs root (the
lab of tests/python/netlab.py).  Prints tables and the goals with PASS/MISS, writes
bench/results/pull.json, exits 0 either way.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(HERE.parent / "network"))  # the lab set-up of bench/network
sys.path.insert(0, str(REPO / "tests" / "python"))  # netlab
for _p in (REPO, REPO / "python"):
    if str(_p) not in sys.path:
        sys.path.insert(0, str(_p))

import pull_metrics as pm  # noqa: E402
from netlab import Host, NetLab, netlab_available  # noqa: E402
from network_cases import DATA_PORT, CaseError, Lab, Proc, ln_env  # noqa: E402

RELAY_PORT = 54400  # where b's daemon data port is advertised: the relay, in front of it
PULL_PORT = 6363  # the producer's port on a (the .lnc default)
PULL_BASE = 54500  # relay links for the pull consumers on b: 127.0.0.1:PULL_BASE + i
TOPIC = "bench.pull"
DEADLINE_MS = 100  # t_max of the hardened consumers
LOSSES = (0.0, 0.05, 0.2)
DELAYS_MS = (1, 10)
PERIODS_MS = (2, 20)
# scheme -> pull_probe options (push has none: it is the daemons' forwarding)
PULL_SCHEMES: dict[str, list[str]] = {
    "poll": ["--poll", "P"],
    "naive": ["--naive"],
    "k1": ["--window", "1", "--deadline", str(DEADLINE_MS)],
    "k2": ["--window", "2", "--deadline", str(DEADLINE_MS)],
    "k3": ["--window", "3", "--deadline", str(DEADLINE_MS)],
}
SCHEMES = ("push", *PULL_SCHEMES)
MODES = {"quick": (3.0, 1.5, 20), "default": (5.0, 1.5, 50), "full": (15.0, 2.0, 200)}
Record = dict[str, Any]


def log(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


class Cell:
    """One combination of loss, delay and period: a relay, a manager case, the numbers."""

    def __init__(self, lab: Lab, index: int, loss: float, delay_ms: int, period_ms: int,
                 seconds: float, warmup: float, rtt_count: int, seed: int,
                 push: bool, schemes: tuple[str, ...] = SCHEMES) -> None:
        self.lab, self.index = lab, index
        self.loss, self.delay_ms, self.period_ms = loss, delay_ms, period_ms
        self.seconds, self.warmup, self.rtt_count = seconds, warmup, rtt_count
        self.seed, self.push = seed, push and "push" in schemes
        self.schemes = schemes
        self.prefix = f"/ln/c{index}"  # a fresh name per cell: never "served already"

    def relay(self, b: Host, a_address: str) -> tuple[subprocess.Popen[str], Path]:
        links = ["--udp", f"{b.address}:{RELAY_PORT}", f"127.0.0.1:{DATA_PORT}",
                 "--tcp", f"{b.address}:{RELAY_PORT}", f"127.0.0.1:{DATA_PORT}"]
        for i in range(len(PULL_SCHEMES)):
            links += ["--udp", f"127.0.0.1:{PULL_BASE + i}", f"{a_address}:{PULL_PORT}"]
        ready = self.lab.path("relay-ready").with_suffix(".json")
        stats = self.lab.path("relay-stats").with_suffix(".json")
        proc = b.popen([sys.executable, "-m", "links_and_nodes.relay.cli", *links,
                        "--loss", str(self.loss), "--delay-ms", str(self.delay_ms),
                        "--seed", str(self.seed), "--ready-file", str(ready),
                        "--stats-file", str(stats)], env=ln_env(b),
                       log=f"relay{self.index}.log")
        deadline = time.monotonic() + 30
        while not ready.exists():
            if proc.poll() is not None or time.monotonic() > deadline:
                raise CaseError(f"ln_relay did not start: see relay{self.index}.log")
            time.sleep(0.05)
        return proc, stats

    def run(self) -> Record:
        probe = self.lab.prog("pull_probe")
        total = self.warmup + self.seconds
        outs = {name: self.lab.path(f"{name}-").with_suffix(".json") for name in SCHEMES}
        procs = [Proc("pub", "a", [probe, "pub", TOPIC, str(self.period_ms * 1000)],
                      ready=True)]
        if self.push:
            procs.append(Proc("push", "b", [probe, "push", TOPIC, str(total),
                                            str(outs["push"])]))
        uri = f"{self.prefix}/{TOPIC}"
        for i, (name, opts) in enumerate(PULL_SCHEMES.items()):
            if name not in self.schemes:
                continue
            opts = [str(self.period_ms) if o == "P" else o for o in opts]
            if name == "k3" and self.rtt_count:
                opts += ["--rtt", str(self.rtt_count)]
            procs.append(Proc(name, "b", [probe, "pull", f"127.0.0.1:{PULL_BASE + i}", uri,
                                          str(total), str(outs[name]), *opts,
                                          "--seed", str(self.seed + i)]))
        extra = (f"\ntopics\n{TOPIC}: pull:ndn-udp, pull_port:{PULL_PORT}, "
                 f"pull_prefix:{self.prefix}\n")
        relay, stats_path = self.relay(self.lab.b, self.lab.a.address)
        try:
            self.lab.managed(self.lab.mgr, procs, [p.name for p in procs if p.name != "pub"],
                             f"cell {self.index}", extra=extra)
        finally:
            relay.send_signal(signal.SIGTERM)
            try:
                relay.wait(30)
            except subprocess.TimeoutExpired:
                relay.kill()
                relay.wait()
        stats = json.loads(stats_path.read_text()) if stats_path.exists() else {}
        return self.evaluate({n: pm.load(p) for n, p in outs.items() if p.exists()}, stats)

    def evaluate(self, runs: dict[str, Record], stats: Record) -> Record:
        period_us = self.period_ms * 1000.0
        w = pm.window(list(runs.values()), period_us, self.warmup)
        out: Record = {"window_s": (w.end_us - w.start_us) / 1e6, "relay": stats,
                       "schemes": {}}
        for name, run in runs.items():
            packets = None
            if name == "push" and stats.get("links"):
                link = stats["links"][0]  # the UDP link in front of b's data port
                packets = link["upstream"]["datagrams_in"] + link["downstream"]["datagrams_in"]
            m = pm.metrics(run, w, packets).as_dict()
            m["state_bytes"] = run.get("state_bytes")
            m["consumer"] = run.get("stats")
            m["t_max_runs"] = (pm.runs_at_t_max(run, DEADLINE_MS, together_us=period_us,
                                                since_us=w.start_us)
                               if name[0] == "k" else None)
            out["schemes"][name] = m
        return out


def size_report() -> str | None:
    script = REPO / "scripts" / "pull-size"
    if not script.exists():
        return None
    try:
        proc = subprocess.run([sys.executable, str(script), str(REPO / "build" / "pull_size.json")],
                              capture_output=True, text=True, timeout=300, cwd=REPO)
    except subprocess.TimeoutExpired:
        return "scripts/pull-size did not finish in 300 s"
    return (proc.stdout + proc.stderr).strip()


def fmt(v: float | None, spec: str = ".1f") -> str:
    return "-" if v is None else format(v, spec)


def print_tables(cells: list[Record]) -> None:
    print(f"{'loss':>5} {'delay':>6} {'period':>7} {'scheme':<7} {'delivered':>9} "
          f"{'AoI mean':>9} {'AoI p99':>8} {'pkts/s':>7} {'RTT p50':>8}")
    for c in cells:
        head = f"{c['loss'] * 100:4.0f}% {c['delay_ms']:3d} ms {c['period_ms']:4d} ms"
        if "error" in c:
            print(f"{head} {'(all)':<7} error: {c['error']}")
            continue
        for name in SCHEMES:
            m = c["schemes"].get(name)
            if m is None:
                print(f"{head} {name:<7} {c.get('missing', {}).get(name, 'not measured')}")
                continue
            print(f"{head} {name:<7} {m['delivered']:9.3f} {m['aoi_mean_ms']:9.1f} "
                  f"{m['aoi_p99_ms']:8.1f} {m['pkts_per_s']:7.0f} "
                  f"{fmt(m['rtt_p50_ms'], '.2f'):>8}")


def goals(cells: list[Record]) -> list[Record]:
    """At 20 % loss, per delay and period: hardened DIT (k = 3) delivery >= 0.9x push, and
    its AoI mean below fixed polling's."""
    out = []
    for c in cells:
        if c["loss"] != 0.2:
            continue
        where = f"20% loss, {c['delay_ms']} ms, {c['period_ms']} ms"
        s = c.get("schemes", {})
        k3, push, poll = s.get("k3"), s.get("push"), s.get("poll")
        ok = k3 is not None and push is not None
        out.append({"goal": "hardened DIT (k=3) delivered >= 0.9x push", "where": where,
                    "value": f"{k3['delivered']:.3f} vs {push['delivered']:.3f}" if ok else
                    "n/a", "pass": bool(ok and k3["delivered"] >= 0.9 * push["delivered"])})
        ok = k3 is not None and poll is not None
        out.append({"goal": "hardened DIT (k=3) AoI mean < fixed polling", "where": where,
                    "value": f"{k3['aoi_mean_ms']:.1f} vs {poll['aoi_mean_ms']:.1f} ms" if ok
                    else "n/a", "pass": bool(ok and k3["aoi_mean_ms"] < poll["aoi_mean_ms"])})
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--quick", action="store_true", help="3 s cells: a smoke run")
    mode.add_argument("--full", action="store_true", help="15 s cells")
    ap.add_argument("--seconds", type=float, help="measured seconds per cell")
    ap.add_argument("--seed", type=int, default=1, help="the relay's seed (default 1)")
    ap.add_argument("--cells", type=int, default=0,
                    help="run only the first N cells (trying the set-up)")
    ap.add_argument("--schemes", default=",".join(SCHEMES),
                    help=f"comma-separated subset of {','.join(SCHEMES)}")
    ap.add_argument("--bin", type=Path, default=REPO / "build" / "release" / "bench" / "pull")
    ap.add_argument("--out", type=Path, default=REPO / "bench" / "results" / "pull.json")
    args = ap.parse_args()
    seconds, warmup, rtt_count = MODES["quick" if args.quick else
                                       "full" if args.full else "default"]
    seconds = args.seconds or seconds
    schemes = tuple(s for s in args.schemes.split(",") if s)
    if not set(schemes) <= set(SCHEMES):
        ap.error(f"unknown scheme in {args.schemes!r} (known: {', '.join(SCHEMES)})")
    result: Record = {"benchmark": "pull", "host": platform.node(), "cpus": os.cpu_count(),
                      "seconds": seconds, "warmup_s": warmup, "seed": args.seed,
                      "deadline_ms": DEADLINE_MS, "cells": [], "goals": []}
    reason = netlab_available()
    if reason is None and not (args.bin / "pull_probe").exists():
        reason = f"{args.bin / 'pull_probe'} is missing: run scons -j2 first"
    if reason is not None:
        print(f"pull benchmark not run: {reason}")
        result["not_run"] = reason
    else:
        with tempfile.TemporaryDirectory(prefix="lnbench-pull-") as tmp, \
                NetLab(Path(tmp) / "lab") as nl:
            lab = Lab(nl, args.bin, host_args={"b": ("--advertise-data-port",
                                                     str(RELAY_PORT))})
            index = 0
            for period in PERIODS_MS:
                for delay in DELAYS_MS:
                    for loss in LOSSES:
                        index += 1
                        if args.cells and index > args.cells:
                            continue
                        cell: Record = {"loss": loss, "delay_ms": delay, "period_ms": period}
                        log(f"cell {index}: loss {loss:.0%}, delay {delay} ms, "
                            f"period {period} ms")
                        c = Cell(lab, index, loss, delay, period, seconds, warmup, rtt_count,
                                 args.seed, push=lab.multihost_missing is None,
                                 schemes=schemes)
                        if lab.multihost_missing is not None:
                            cell["missing"] = {"push": f"not available: "
                                                       f"{lab.multihost_missing}"}
                        try:
                            cell.update(c.run())
                        except (CaseError, ValueError, OSError) as exc:
                            cell["error"] = str(exc)
                            log(f"  error: {exc}")
                        result["cells"].append(cell)
        print_tables(result["cells"])
        result["goals"] = goals(result["cells"])
        print()
        for g in result["goals"]:
            print(f"{'PASS' if g['pass'] else 'MISS'}  {g['goal']} ({g['where']}): "
                  f"{g['value']}")
        states = {m.get("state_bytes") for c in result["cells"]
                  for m in c.get("schemes", {}).values() if m.get("state_bytes")}
        if states:
            print(f"consumer state (sizeof ln_pull_sub): {', '.join(map(str, states))} bytes")
    sizes = size_report()
    if sizes is not None:
        print("\nscripts/pull-size:\n" + sizes)
        result["size_report"] = sizes
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"\nwritten to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
