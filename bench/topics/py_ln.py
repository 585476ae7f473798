"""Python side of the topic benchmark over links_and_nodes: the roles of lat_ln.c (copy and
full modes) and thr_ln.c with the same arguments and output, written as a user would
(pub.write() and sub.read(); zero-copy: `with pub.loan()` and `with sub.borrow()`, zc touching
the first and last 8 bytes, full copying a whole bytearray into the loan and the borrowed
sample out whole with ctypes.memmove).  The manager comes from $LN_MANAGER.  See
bench_topics.py."""

from __future__ import annotations

import ctypes
import json
import os
import sys
import time
from array import array
from collections.abc import Callable
from functools import partial
from pathlib import Path

from payload import Payload
from receipts import Receipts, minflt

import links_and_nodes as ln

MD_DIR = Path(__file__).resolve().parents[1] / "md"
MDS = {64: "lnbench/sample_64", 4096: "lnbench/sample_4k", 1 << 20: "lnbench/sample_1m",
       4 << 20: "lnbench/sample_4m", 16 << 20: "lnbench/sample_16m",
       64 << 20: "lnbench/sample_64m"}
USAGE = """usage: py_ln.py pong PREFIX SIZE TOTAL [WARMUP [copy|full]]
       | ping PREFIX SIZE COUNT WARMUP OUT [copy|full]
       | sub TOPIC SIZE COUNT BUFFERS [copy|zc|full WARM]
       | pub TOPIC SIZE COUNT wait|nowait [copy|zc|full WARM SECONDS]
Every role ends with a JSON line that has its minor page faults (minflt) from sample WARM on."""
U64 = ctypes.c_uint64


def ready() -> None:
    print("ready", flush=True)


def echo_full(pub: ln.publisher, sub: ln.subscriber, size: int) -> None:
    """Borrow the next sample and copy it whole into a loan sent back."""
    with sub.borrow() as got, pub.loan() as msg:
        ctypes.memmove(ctypes.addressof(msg), ctypes.addressof(got), size)


def pong(clnt: ln.client, prefix: str, md: str, total: int, warmup: int, full: bool) -> None:
    pub = clnt.publish(f"{prefix}.pong", md)
    sub = clnt.subscribe(f"{prefix}.ping", md)
    size = ctypes.sizeof(pub.packet)
    ready()
    faults = minflt()
    for i in range(total):
        if i == warmup:
            faults = minflt()
        if full:
            echo_full(pub, sub, size)
        else:
            pub.write(sub.read())
    print(json.dumps({"minflt": minflt() - faults, "samples": total - min(warmup, total)}))


def round_trip_full(pub: ln.publisher, sub: ln.subscriber, src: Payload, dst: Payload,
                    i: int) -> int:
    """Copy the stamped source whole into a loan, then the borrowed reply whole out."""
    src.stamp(i)
    with pub.loan() as msg:
        src.into(ctypes.addressof(msg))
    with sub.borrow() as got:
        return dst.take(ctypes.addressof(got), "py_ln")


def ping(clnt: ln.client, prefix: str, md: str, count: int, warmup: int, out: str,
         full: bool) -> None:
    pub = clnt.publish(f"{prefix}.ping", md)
    sub = clnt.subscribe(f"{prefix}.pong", md)
    rtt = array("Q", bytes(8 * count))
    pkt, now = pub.packet, time.perf_counter_ns
    src, dst = (Payload(ctypes.sizeof(pkt)), Payload(ctypes.sizeof(pkt))) if full else (None, None)
    faults = 0
    for i in range(warmup + count):
        if i == warmup:
            faults = minflt()
        t0 = now()
        if src is not None and dst is not None:
            back = round_trip_full(pub, sub, src, dst, i)
        else:
            pkt.counter = i
            pub.write()
            got = sub.read()
            back = -1 if got is None else got.counter
        t1 = now()
        if back != i:
            sys.exit(f"py_ln: round trip {i} came back wrong")
        if i >= warmup:
            rtt[i - warmup] = t1 - t0
    print(json.dumps({"minflt": minflt() - faults, "samples": count}))
    with open(out, "wb") as f:
        rtt.tofile(f)


def read_copy(sub: ln.subscriber, timeout: float) -> int | None:
    pkt = sub.read(timeout=timeout)
    return None if pkt is None else pkt.counter


def read_zc(sub: ln.subscriber, timeout: float) -> int | None:
    """One sample by borrow: its first and last 8 bytes, checked against each other."""
    with sub.borrow(timeout=timeout) as msg:
        if msg is None:
            return None
        counter = msg.counter
        tail = U64.from_address(ctypes.addressof(msg) + ctypes.sizeof(msg) - 8).value
    if tail != counter:
        sys.exit(f"py_ln: torn sample {counter}/{tail}")
    return counter


def read_full(sub: ln.subscriber, timeout: float, dst: Payload) -> int | None:
    """One sample by borrow, copied out whole before it is released."""
    with sub.borrow(timeout=timeout) as msg:
        if msg is None:
            return None
        return dst.take(ctypes.addressof(msg), "py_ln")


def subscriber(clnt: ln.client, topic: str, md: str, count: int, buffers: int, mode: str,
               warm: int) -> None:
    sub = clnt.subscribe(topic, md, buffers=buffers)
    if mode == "full":
        read: Callable[[ln.subscriber, float], int | None] = partial(
            read_full, dst=Payload(ctypes.sizeof(sub.packet)))
    else:
        read = read_zc if mode == "zc" else read_copy
    tally = Receipts(warm)
    ready()
    while not tally.done(count):
        counter = read(sub, 2.0 if tally.received else 60.0)
        if counter is None:
            break
        tally.got(counter)
    tally.report(sub.overruns)


def publisher(clnt: ln.client, topic: str, md: str, count: int, wait: bool, mode: str,
              warm: int, seconds: float) -> None:
    pub = clnt.publish(topic, md, wait_for_subscribers=wait)
    pkt = pub.packet
    tail_offset = ctypes.sizeof(pkt) - 8
    src = Payload(ctypes.sizeof(pkt)) if mode == "full" else None
    ready()
    now = time.perf_counter_ns
    t0 = now()
    stop = t0 + int(seconds * 1e9) if seconds > 0 else None
    faults = minflt()
    sent = 0
    for i in range(count):
        if i == warm:
            faults = minflt()
        last = stop is not None and (i & 15) == 0 and now() > stop
        counter = count - 1 if last else i
        if src is not None:  # the whole sample from a bytearray into the loan
            src.stamp(counter)
            with pub.loan() as msg:
                src.into(ctypes.addressof(msg))
        elif mode == "zc":
            with pub.loan() as msg:  # zero-copy: write in the ring, commit at the end
                msg.counter = counter
                U64.from_address(ctypes.addressof(msg) + tail_offset).value = counter
        else:
            pkt.counter = counter
            pub.write()
        sent += 1
        if last:
            break
    elapsed = (now() - t0) * 1e-9
    print(json.dumps({"sent": sent, "elapsed_s": elapsed,
                      "minflt": minflt() - faults if sent > warm else 0,
                      "fault_samples": max(0, sent - warm)}))


def main(argv: list[str]) -> int:
    if len(argv) < 5 or argv[1] not in ("pong", "ping", "sub", "pub"):
        print(USAGE, file=sys.stderr)
        return 2
    role, name, md = argv[1], argv[2], MDS[int(argv[3])]
    ln.add_message_definition_dir(MD_DIR)
    with ln.client(f"py_ln_{role}", os.environ["LN_MANAGER"]) as clnt:
        mode = argv[6] if len(argv) > 6 else "copy"
        warm = int(argv[7]) if len(argv) > 7 and role in ("sub", "pub") else 0
        if role == "pong":
            pong(clnt, name, md, int(argv[4]), int(argv[5]) if len(argv) > 5 else 0,
                 len(argv) > 6 and argv[6] == "full")
        elif role == "ping":
            ping(clnt, name, md, int(argv[4]), int(argv[5]), argv[6],
                 len(argv) > 7 and argv[7] == "full")
        elif role == "sub":
            subscriber(clnt, name, md, int(argv[4]), int(argv[5]), mode, warm)
        else:
            publisher(clnt, name, md, int(argv[4]), argv[5] == "wait", mode, warm,
                      float(argv[8]) if len(argv) > 8 else 0.0)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
