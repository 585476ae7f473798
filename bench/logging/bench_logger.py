"""Topic logger benchmark: what an enabled ln_daemon logger costs the publisher, and how fast
a publisher it keeps up with (docs/daemon.md, "Topic logging").

Goals and measurements, each in the same run:
  (a) publish cost: ns per ln_write in a tight loop of a 64 B and a 4 KiB topic, with the
      topic's daemon logger disabled (the baseline) and enabled, in alternating rounds;
      goal: enabled <= 1.05x the baseline (medians).
  (b) the highest publish rate a logger keeps without gaps (missed == 0) for 64 B and 1 MiB
      samples, with the publisher's default ring (2 slots) and a deeper one (64 slots): the
      rate doubles until the publisher cannot keep it or the logger misses most samples;
      every step's missed count is shown.  Measured, no goal.

A private ln_manager (for ln_write) and a private ln_daemon (for the logger, driven directly
through daemon_client) run for the benchmark; the publisher is bench_logger_pub, built by
scons into build/release/bench/logging/ (this script builds nothing).  Prints tables, writes
bench/results/logger.json, exits 0 whether the goal is met or not.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import platform
import signal
import statistics
import subprocess
import sys
import tempfile
import time
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(REPO / "python"))  # measure this checkout, not an installed one

from links_and_nodes.manager.frontends.launch import ManagerProcess, segments, start_manager  # noqa: E402
from links_and_nodes.manager.processes import daemon_client as dc  # noqa: E402
from links_and_nodes.manager.processes import daemon_keys as dk  # noqa: E402
from links_and_nodes.manager.processes import daemon_launch as dl  # noqa: E402
from links_and_nodes.manager.processes import daemon_wire as dw  # noqa: E402

PUBLISHER = REPO / "build" / "release" / "bench" / "logging" / "bench_logger_pub"
GOAL_COST_RATIO = 1.05
MIB = 1 << 20
WAIT = 60.0  # seconds: only an upper bound while waiting for the logger to catch up


def log(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


# ---- processes ------------------------------------------------------------------------------


@dataclass
class Daemon:
    proc: subprocess.Popen[bytes]
    port: int
    key: bytes

    @classmethod
    def start(cls, tmp: Path, memory: str) -> Daemon:
        key_file = tmp / "daemon.key"
        key = dk.create_key_file(key_file)
        proc = subprocess.Popen([dl.daemon_executable(), "--port", "0", "--bind", "127.0.0.1",
                                 "--key-file", str(key_file), "--log", str(tmp / "daemon.log"),
                                 "--foreground", "--logger-memory", memory],
                                stdout=subprocess.PIPE, stdin=subprocess.DEVNULL)
        assert proc.stdout is not None
        line = proc.stdout.readline().decode()
        if " listening on " not in line:
            proc.wait()
            raise RuntimeError(f"ln_daemon did not start: {line!r}")
        port = int(line.split(" listening on ", 1)[1].split()[0].rsplit(":", 1)[1])
        return cls(proc, port, key)

    def stop(self) -> int:
        self.proc.send_signal(signal.SIGTERM)
        try:
            return self.proc.wait(30)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            return self.proc.wait()


class Publisher:
    """bench_logger_pub on one topic; `ring` is the shm name of the topic's ring."""

    def __init__(self, manager: ManagerProcess, topic: str, size: int, buffers: int) -> None:
        before = set(segments(manager.instance))
        self.proc = subprocess.Popen([str(PUBLISHER), topic, str(size), str(buffers)],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                                     env=manager.env)
        assert self.proc.stdout is not None
        ready = self.proc.stdout.readline().split()
        if not ready or ready[0] != "ready":
            self.proc.wait()
            raise RuntimeError(f"bench_logger_pub did not start for {topic}")
        self.md_name, self.layout_hash = ready[1], int(ready[2])
        (segment,) = set(segments(manager.instance)) - before
        self.ring = "/" + segment
        self.size = size
        self.slots = buffers + 1

    def ask(self, command: str) -> dict[str, Any]:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write(command + "\n")
        self.proc.stdin.flush()
        answer: dict[str, Any] = json.loads(self.proc.stdout.readline())
        if "error" in answer:
            raise RuntimeError(f"bench_logger_pub: {command}: {answer['error']}")
        return answer

    def close(self) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write("quit\n")
        self.proc.stdin.close()
        try:
            self.proc.wait(30)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


async def caught_up(client: dc.DaemonClient, logger: str, topic: str,
                    published: int) -> dw.LoggerTopicStatus:
    """The logger's status once every sample published is received or counted missed."""
    deadline = time.monotonic() + WAIT
    while True:
        (status,) = (await client.logger_status(logger)).topics
        assert status.topic == topic
        if status.received + status.missed >= published:
            return status
        if time.monotonic() > deadline:
            raise RuntimeError(f"logger {logger} got only {status.received} + "
                               f"{status.missed} missed of {published} samples")
        await asyncio.sleep(0.01)


# ---- (a) publish cost ---------------------------------------------------------------------


async def publish_cost(client: dc.DaemonClient, manager: ManagerProcess, size: int, count: int,
                       rounds: int) -> dict[str, Any]:
    topic, logger = f"/bench/cost{size}", f"cost{size}"
    pub = Publisher(manager, topic, size, 1)
    try:
        await client.logger_topic(logger, topic, pub.ring, pub.md_name, pub.layout_hash, size,
                                  max(8, (16 * MIB) // (size + 16)))
        base: list[float] = []
        logged: list[float] = []
        received = missed = 0
        for r in range(rounds):  # alternating which goes first cancels slow drifts
            for enabled in ((False, True) if r % 2 == 0 else (True, False)):
                await client.logger_enable(logger, enable=enabled, clear=True)
                answer = await asyncio.to_thread(pub.ask, f"cost {count}")
                (logged if enabled else base).append(answer["ns_per_write"])
                if enabled:  # the warm-up and the timed writes
                    status = await caught_up(client, logger, topic, count // 10 + 1 + count)
                    received += status.received
                    missed += status.missed
        await client.logger_remove(logger)
    finally:
        pub.close()
    ratio = statistics.median(logged) / statistics.median(base)
    return {"size": size, "ring_slots": pub.slots, "count": count, "rounds": rounds,
            "baseline_ns": base, "logger_ns": logged,
            "baseline_median_ns": statistics.median(base),
            "logger_median_ns": statistics.median(logged), "ratio": ratio,
            "goal": GOAL_COST_RATIO, "met": ratio <= GOAL_COST_RATIO,
            "logger_received": received, "logger_missed": missed}


# ---- (b) the highest rate without gaps ----------------------------------------------------------


async def gap_free_rate(client: dc.DaemonClient, manager: ManagerProcess, size: int,
                        buffers: int, rates: list[float], seconds: float) -> dict[str, Any]:
    """Steps through `rates` until the publisher cannot keep one or the logger misses most
    samples; the highest gap-free rate is the last one below which no step missed any."""
    topic, logger = f"/bench/rate{size}x{buffers}", f"rate{size}x{buffers}"
    pub = Publisher(manager, topic, size, buffers)
    steps: list[dict[str, Any]] = []
    kept: float | None = None
    gap_free = True
    ended = "the highest rate tried"
    try:
        await client.logger_topic(logger, topic, pub.ring, pub.md_name, pub.layout_hash, size,
                                  max(4, (16 * MIB) // (size + 16)))
        for hz in rates:
            await client.logger_enable(logger, enable=False)
            await client.logger_enable(logger, clear=True)
            answer = await asyncio.to_thread(pub.ask, f"rate {hz} {seconds}")
            status = await caught_up(client, logger, topic, answer["published"])
            steps.append({"rate_hz": hz, **answer, "received": status.received,
                          "missed": status.missed})
            log(f"  {size} B, {pub.slots} slots, {hz:.0f} Hz: achieved "
                f"{answer['achieved_hz']:.0f} Hz, missed {status.missed}")
            if answer["achieved_hz"] < 0.95 * hz:
                ended = f"the publisher reached only {answer['achieved_hz']:.0f} Hz"
                break
            gap_free = gap_free and status.missed == 0
            if gap_free:
                kept = hz
            if status.missed > answer["published"] // 2:
                ended = "the logger missed most samples"
                break
        await client.logger_remove(logger)
    finally:
        pub.close()
    return {"size": size, "ring_slots": pub.slots, "seconds_per_step": seconds,
            "highest_gap_free_hz": kept, "ended": ended, "steps": steps}


# ---- report ---------------------------------------------------------------------------------


def size_text(size: int) -> str:
    return f"{size // MIB} MiB" if size >= MIB else f"{size // 1024} KiB" if size >= 1024 \
        else f"{size} B"


def print_report(result: dict[str, Any]) -> None:
    facts = result["facts"]
    print(f"\ntopic logger benchmark — commit {facts['commit']}, {facts['cpu_count']} CPUs, "
          f"load {facts['load_start']} -> {facts['load_end']}")
    print(f"\n(a) publish cost, ns per ln_write, tight loop, no subscriber "
          f"(goal: logger <= {GOAL_COST_RATIO:.2f}x baseline)")
    print(f"{'size':>8} {'slots':>5} {'baseline':>9} {'logger':>9} {'ratio':>6}  "
          f"{'goal':<4}  logger got / missed")
    for c in result["cost"]:
        print(f"{size_text(c['size']):>8} {c['ring_slots']:>5} {c['baseline_median_ns']:>9.1f} "
              f"{c['logger_median_ns']:>9.1f} {c['ratio']:>6.3f}  "
              f"{'PASS' if c['met'] else 'MISS':<4}  {c['logger_received']} / "
              f"{c['logger_missed']}")
    print("\n(b) highest publish rate a logger keeps without gaps "
          f"({result['rate'][0]['seconds_per_step'] if result['rate'] else 0:g} s per rate; "
          "missed / published at each rate)")
    print(f"{'size':>8} {'slots':>5} {'gap-free Hz':>12}  steps")
    for r in result["rate"]:
        kept = f"{r['highest_gap_free_hz']:.0f}" if r["highest_gap_free_hz"] else "none"
        steps = ", ".join(f"{s['rate_hz'] / 1000:g}k: {s['missed']}/{s['published']}"
                          for s in r["steps"])
        print(f"{size_text(r['size']):>8} {r['ring_slots']:>5} {kept:>12}  {steps}; "
              f"{r['ended']}")


async def run(args: argparse.Namespace, manager: ManagerProcess,
              daemon: Daemon) -> dict[str, Any]:
    client = await dc.DaemonClient.connect("127.0.0.1", daemon.port, daemon.key,
                                           manager.instance)
    try:
        cost = []
        for size, count in ((64, 2_000_000), (4096, 200_000)):
            log(f"publish cost, {size} B")
            cost.append(await publish_cost(client, manager, size,
                                           count // 10 if args.quick else count,
                                           3 if args.quick else args.rounds))
        rate = []
        small = [1000.0 * 2 ** i for i in range(12)]  # 1 kHz .. 2 MHz
        large = [125.0 * 2 ** i for i in range(9)]  # 125 Hz .. 32 kHz
        seconds = 0.3 if args.quick else args.seconds
        for size, rates in ((64, small), (MIB, large)):
            for buffers in (1, 63):
                log(f"gap-free rate, {size} B, {buffers + 1} slots")
                rate.append(await gap_free_rate(client, manager, size, buffers, rates, seconds))
    finally:
        await client.close()
    return {"cost": cost, "rate": rate}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a smoke run, not for numbers")
    parser.add_argument("--rounds", type=int, default=11, help="rounds per publish cost case")
    parser.add_argument("--seconds", type=float, default=1.0, help="seconds per rate step")
    parser.add_argument("--json", type=Path, default=REPO / "bench" / "results" / "logger.json")
    args = parser.parse_args()
    if not os.access(PUBLISHER, os.X_OK):
        log(f"{PUBLISHER} is missing: run scons -j2 first")
        return 1
    commit = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip() or "unknown"
    facts = {"started": time.strftime("%Y-%m-%d %H:%M:%S"), "quick": args.quick,
             "commit": commit, "machine": platform.machine(), "kernel": platform.release(),
             "cpu_count": os.cpu_count(), "load_start": os.getloadavg()[0]}
    with tempfile.TemporaryDirectory(prefix="ln_bench_logger.") as tmp_dir:
        tmp = Path(tmp_dir)
        instance = f"benchlog{os.getpid()}x{uuid.uuid4().hex[:6]}"
        manager = start_manager(instance, tmp / "runtime", tmp / "manager.log",
                                "--log-level", "warning")
        daemon = Daemon.start(tmp, "1G")
        try:
            result: dict[str, Any] = asyncio.run(run(args, manager, daemon))
        finally:
            daemon_status = daemon.stop()
            manager.stop()
            for name in segments(instance):
                Path("/dev/shm", name).unlink(missing_ok=True)
    facts["load_end"] = os.getloadavg()[0]
    facts["daemon_exit"] = daemon_status
    result = {"facts": facts, **result}
    print_report(result)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=1) + "\n")
    print(f"\nwritten to {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
