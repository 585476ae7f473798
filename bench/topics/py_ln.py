"""Python side of the topic benchmark over links_and_nodes: the roles of lat_ln.c (copy mode)
and thr_ln.c with the same arguments and output, written as a user would (pub.write(),
sub.read()).  The manager comes from $LN_MANAGER.  See bench_topics.py."""

from __future__ import annotations

import json
import os
import sys
import time
from array import array
from pathlib import Path

import links_and_nodes as ln

MD_DIR = Path(__file__).resolve().parents[1] / "md"
MDS = {64: "lnbench/sample_64", 4096: "lnbench/sample_4k", 1 << 20: "lnbench/sample_1m",
       4 << 20: "lnbench/sample_4m"}
USAGE = """usage: py_ln.py pong PREFIX SIZE TOTAL | ping PREFIX SIZE COUNT WARMUP OUT
       | sub TOPIC SIZE COUNT BUFFERS | pub TOPIC SIZE COUNT wait|nowait"""


def ready() -> None:
    print("ready", flush=True)


def pong(clnt: ln.client, prefix: str, md: str, total: int) -> None:
    pub = clnt.publish(f"{prefix}.pong", md)
    sub = clnt.subscribe(f"{prefix}.ping", md)
    ready()
    for _ in range(total):
        pub.write(sub.read())


def ping(clnt: ln.client, prefix: str, md: str, count: int, warmup: int, out: str) -> None:
    pub = clnt.publish(f"{prefix}.ping", md)
    sub = clnt.subscribe(f"{prefix}.pong", md)
    rtt = array("Q", bytes(8 * count))
    pkt, now = pub.packet, time.perf_counter_ns
    for i in range(warmup + count):
        t0 = now()
        pkt.counter = i
        pub.write()
        got = sub.read()
        t1 = now()
        if got is None or got.counter != i:
            sys.exit(f"py_ln: round trip {i} came back wrong")
        if i >= warmup:
            rtt[i - warmup] = t1 - t0
    with open(out, "wb") as f:
        rtt.tofile(f)


def subscriber(clnt: ln.client, topic: str, md: str, count: int, buffers: int) -> None:
    sub = clnt.subscribe(topic, md, buffers=buffers)
    received = disorder = last = first_ns = last_ns = 0
    now = time.perf_counter_ns
    ready()
    while received == 0 or last + 1 < count:
        pkt = sub.read(timeout=2.0 if received else 60.0)
        if pkt is None:
            break
        last_ns = now()
        counter = pkt.counter
        if received == 0:
            first_ns = last_ns
        elif counter <= last:
            disorder += 1
        received += 1
        last = counter
    print(json.dumps({"received": received, "overruns": sub.overruns, "disorder": disorder,
                      "elapsed_s": (last_ns - first_ns) * 1e-9}))


def publisher(clnt: ln.client, topic: str, md: str, count: int, wait: bool) -> None:
    pub = clnt.publish(topic, md, wait_for_subscribers=wait)
    pkt = pub.packet
    ready()
    t0 = time.perf_counter_ns()
    for i in range(count):
        pkt.counter = i
        pub.write()
    elapsed = (time.perf_counter_ns() - t0) * 1e-9
    print(json.dumps({"sent": count, "elapsed_s": elapsed}))


def main(argv: list[str]) -> int:
    if len(argv) < 5 or argv[1] not in ("pong", "ping", "sub", "pub"):
        print(USAGE, file=sys.stderr)
        return 2
    role, name, md = argv[1], argv[2], MDS[int(argv[3])]
    ln.add_message_definition_dir(MD_DIR)
    with ln.client(f"py_ln_{role}", os.environ["LN_MANAGER"]) as clnt:
        if role == "pong":
            pong(clnt, name, md, int(argv[4]))
        elif role == "ping":
            ping(clnt, name, md, int(argv[4]), int(argv[5]), argv[6])
        elif role == "sub":
            subscriber(clnt, name, md, int(argv[4]), int(argv[5]))
        else:
            publisher(clnt, name, md, int(argv[4]), argv[5] == "wait")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
