"""Python subscriber of the waitset benchmark: the `sub` role of waitset_bench.c for one topic,
written as a user would: `sub.read()` (blocking) or `await sub.read_async()` in asyncio.
Each sample's one-way latency is CLOCK_MONOTONIC after the read minus the stamp the
publisher wrote into it; the same JSON line and latency file as the C subscriber.  The
manager comes from $LN_MANAGER.  See bench_waitset.py."""

from __future__ import annotations

import asyncio
import ctypes
import json
import os
import resource
import sys
import time
from array import array
from pathlib import Path
from typing import Any

import links_and_nodes as ln

MD_DIR = Path(__file__).resolve().parents[1] / "md"
MD = "lnbench/sample_64"
BUFFERS = 16  # queued, as the C subscriber: a late read is timed, not skipped
STAMP_OFFSET = 8  # the publisher's CLOCK_MONOTONIC (ns) after the counter
USAGE = "usage: py_waitset.py read|async TOPIC COUNT WARMUP OUT"


def cpu_s() -> float:
    ru = resource.getrusage(resource.RUSAGE_SELF)
    return ru.ru_utime + ru.ru_stime


class Receipts:
    """The C subscriber's bookkeeping: latencies after the warm-up, losses, CPU time and
    waits from the first counted sample on."""

    def __init__(self, count: int, warmup: int) -> None:
        self.count, self.warmup = count, warmup
        self.lat = array("Q", bytes(8 * count))
        self.got = self.waits = self.lost = self.next = 0
        self.cpu0 = self.t0 = 0.0

    def took(self, pkt: Any, now: int) -> bool:
        """One sample read at `now`; True once the last one came."""
        counter = pkt.counter
        stamp = ctypes.c_uint64.from_address(ctypes.addressof(pkt) + STAMP_OFFSET).value
        if counter >= self.warmup and self.got == 0:
            self.cpu0, self.t0, self.waits = cpu_s(), now * 1e-9, 0
        if counter >= self.next:
            self.lost += counter - self.next
        self.next = counter + 1
        if counter >= self.warmup and self.got < self.count:
            self.lat[self.got] = now - stamp
            self.got += 1
        return counter + 1 >= self.warmup + self.count

    def report(self, out: str) -> None:
        cpu, wall = cpu_s() - self.cpu0, time.monotonic_ns() * 1e-9 - self.t0
        print(
            json.dumps(
                {
                    "samples": self.got,
                    "lost": self.lost,
                    "waits": self.waits,
                    "cpu_s": cpu,
                    "wall_s": wall,
                    "inports": 1,
                }
            ),
            flush=True,
        )
        with open(out, "wb") as f:
            self.lat[: self.got].tofile(f)


def blocking(sub: ln.subscriber, r: Receipts) -> None:
    now = time.monotonic_ns
    while True:
        pkt = sub.read(timeout=10.0)
        t = now()
        if pkt is None:
            sys.exit("py_waitset: no sample within 10 s")
        r.waits += 1
        if r.took(pkt, t):
            return


async def awaiting(sub: ln.subscriber, r: Receipts) -> None:
    now = time.monotonic_ns
    while True:
        pkt = await sub.read_async(timeout=10.0)
        t = now()
        if pkt is None:
            sys.exit("py_waitset: no sample within 10 s")
        r.waits += 1
        if r.took(pkt, t):
            return


def main(argv: list[str]) -> int:
    if len(argv) != 6 or argv[1] not in ("read", "async"):
        print(USAGE, file=sys.stderr)
        return 2
    mode, topic, count, warmup, out = argv[1], argv[2], int(argv[3]), int(argv[4]), argv[5]
    ln.add_message_definition_dir(MD_DIR)
    r = Receipts(count, warmup)
    with ln.client("py_waitset_sub", os.environ["LN_MANAGER"]) as clnt:
        sub = clnt.subscribe(topic, MD, buffers=BUFFERS)
        print("ready", flush=True)
        if mode == "read":
            blocking(sub, r)
        else:
            asyncio.run(awaiting(sub, r))
        r.report(out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
