"""The pyzmq reference of the topic benchmark over ipc://: REQ/REP ping-pong and PUSH/PULL or
PUB/SUB throughput with the same arguments and output as py_ln.py, using pyzmq's defaults
(copying sends and receives, high-water mark 1,000).  See bench_topics.py."""

from __future__ import annotations

import json
import struct
import sys
import time
from array import array

import zmq
from receipts import Receipts

USAGE = """usage: py_zmq.py pong ADDR SIZE TOTAL | ping ADDR SIZE COUNT WARMUP OUT
       | pull|sub ADDR SIZE COUNT | push|pub ADDR SIZE COUNT"""
COUNTER = struct.Struct("<Q")


def ready() -> None:
    print("ready", flush=True)


def pong(ctx: zmq.Context, addr: str, total: int) -> None:
    sock = ctx.socket(zmq.REP)
    sock.bind(addr)
    ready()
    for _ in range(total):
        sock.send(sock.recv())
    sock.close(linger=1000)


def ping(ctx: zmq.Context, addr: str, size: int, count: int, warmup: int, out: str) -> None:
    sock = ctx.socket(zmq.REQ)
    sock.connect(addr)
    buf = bytearray(size)
    rtt = array("Q", bytes(8 * count))
    now, pack, unpack = time.perf_counter_ns, COUNTER.pack_into, COUNTER.unpack_from
    for i in range(warmup + count):
        t0 = now()
        pack(buf, 0, i)
        sock.send(buf)
        reply = sock.recv()
        t1 = now()
        if unpack(reply)[0] != i:
            sys.exit(f"py_zmq: round trip {i} came back wrong")
        if i >= warmup:
            rtt[i - warmup] = t1 - t0
    sock.close()
    with open(out, "wb") as f:
        rtt.tofile(f)


def receiver(ctx: zmq.Context, kind: int, addr: str, count: int) -> None:
    sock = ctx.socket(kind)
    if kind == zmq.SUB:
        sock.setsockopt(zmq.SUBSCRIBE, b"")
    sock.bind(addr)
    tally = Receipts()
    unpack = COUNTER.unpack_from
    ready()
    while not tally.done(count):
        if not sock.poll(2000 if tally.received else 60000):
            break
        tally.got(unpack(sock.recv())[0])
    tally.report()
    sock.close(linger=0)
    done = ctx.socket(zmq.PUSH)
    done.connect(addr + ".done")
    done.send(b"done")
    done.close(linger=5000)


def sender(ctx: zmq.Context, kind: int, addr: str, size: int, count: int) -> None:
    # The sender stays connected until the receiver says it is done: a sender that closes
    # early makes libzmq drop what the receiving engine had read but not yet queued.
    done = ctx.socket(zmq.PULL)
    done.bind(addr + ".done")
    sock = ctx.socket(kind)
    sock.connect(addr)
    if kind == zmq.PUB:
        time.sleep(0.5)  # let the subscription reach the publisher (zmq's "slow joiner")
    buf = bytearray(size)
    pack = COUNTER.pack_into
    ready()
    t0 = time.perf_counter_ns()
    for i in range(count):
        pack(buf, 0, i)
        sock.send(buf)
    elapsed = (time.perf_counter_ns() - t0) * 1e-9
    print(json.dumps({"sent": count, "elapsed_s": elapsed}))
    done.poll(120_000)
    sock.close(linger=0)
    done.close(linger=0)


def main(argv: list[str]) -> int:
    roles = ("pong", "ping", "pull", "sub", "push", "pub")
    if len(argv) < 5 or argv[1] not in roles:
        print(USAGE, file=sys.stderr)
        return 2
    role, addr, size, count = argv[1], argv[2], int(argv[3]), int(argv[4])
    ctx = zmq.Context()
    if role == "pong":
        pong(ctx, addr, count)
    elif role == "ping":
        ping(ctx, addr, size, count, int(argv[5]), argv[6])
    elif role in ("pull", "sub"):
        receiver(ctx, zmq.PULL if role == "pull" else zmq.SUB, addr, count)
    else:
        sender(ctx, zmq.PUSH if role == "push" else zmq.PUB, addr, size, count)
    ctx.term()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
