"""The programs of bench_zenoh.py, run in the lab's hosts: ping-pong and a one-way stream, once
through links_and_nodes topics (forwarded by the daemons or by two ln_zenoh bridges: the
program is the same) and once over plain Zenoh pub/sub between two Python processes.

    zb_bench_peer.py ln-pong SIZE [--transport udp]       echo bench.ping on bench.pong
    (every mode takes --name NAME for topics NAME.ping, ... and keys NAME/ping, ...)
    zb_bench_peer.py ln-ping SIZE COUNT WARMUP            COUNT round trips -> JSON
    zb_bench_peer.py ln-sink SIZE COUNT                    count bench.data -> JSON
    zb_bench_peer.py ln-source SIZE COUNT                  publish COUNT on bench.data
    zb_bench_peer.py z-pong SIZE --listen EP
    zb_bench_peer.py z-ping SIZE COUNT WARMUP --connect EP
    zb_bench_peer.py z-sink SIZE COUNT --listen EP
    zb_bench_peer.py z-source SIZE COUNT --connect EP

SIZE is 64 or 1048576 (md lnbench/sample_64, lnbench/sample_1m).  Servers print "ready" once
they can be used; measuring sides print one JSON line.
"""

from __future__ import annotations

import argparse
import json
import threading
import time
from typing import Any

MDS = {64: "lnbench/sample_64", 1 << 20: "lnbench/sample_1m"}
IDLE_S = 3.0  # a sink ends when nothing came for this long
RESEND_S = 1.0  # a ping not answered within this is sent again (a lost sample)


def _stats(rtts: list[int]) -> dict[str, Any]:
    one_way = sorted(r / 2000.0 for r in rtts)  # µs
    pick = lambda q: one_way[min(len(one_way) - 1, int(q * len(one_way)))]  # noqa: E731
    return {"round_trips": len(rtts), "p50_us": pick(0.5), "p99_us": pick(0.99),
            "max_us": one_way[-1]}


# ---- links_and_nodes ----------------------------------------------------------------------------

def ln_pong(args: argparse.Namespace) -> None:
    import links_and_nodes as ln

    clnt = ln.client("bench_pong")
    sub = clnt.subscribe(f"{args.name}.ping", MDS[args.size], buffers=16, transport=args.transport)
    pub = clnt.publish(f"{args.name}.pong", MDS[args.size])
    print("ready", flush=True)
    while True:
        msg = sub.read(timeout=1.0)
        if msg is not None:
            pub.write(msg)


def ln_ping(args: argparse.Namespace) -> None:
    import links_and_nodes as ln

    clnt = ln.client("bench_ping")
    pub = clnt.publish(f"{args.name}.ping", MDS[args.size])
    sub = clnt.subscribe(f"{args.name}.pong", MDS[args.size], buffers=16, transport=args.transport)
    rtts: list[int] = []
    resent = 0
    for i in range(1, args.count + args.warmup + 1):
        pub.packet.counter = i
        t0 = time.perf_counter_ns()
        pub.write()
        while True:
            msg = sub.read(timeout=RESEND_S)
            if msg is None:
                resent += 1
                t0 = time.perf_counter_ns()
                pub.write()
                continue
            if msg.counter == i:
                break
        if i > args.warmup:
            rtts.append(time.perf_counter_ns() - t0)
    print(json.dumps({**_stats(rtts), "resent": resent}), flush=True)


def ln_sink(args: argparse.Namespace) -> None:
    import links_and_nodes as ln

    clnt = ln.client("bench_sink")
    sub = clnt.subscribe(f"{args.name}.data", MDS[args.size], buffers=1024 if args.size == 64 else 64,
                         transport=args.transport)
    print("ready", flush=True)

    def borrow() -> bool:
        try:
            with sub.borrow(timeout=IDLE_S) as msg:
                return msg is not None
        except ln.LnOverrunError:  # it came, and was overwritten while borrowed
            return True

    # Large samples zero-copy, as z-sink, which does not copy the payload out of Zenoh's
    # sample either; small ones with one read (one call instead of borrow and release).
    _count(borrow if args.size > 64 else lambda: sub.read(timeout=IDLE_S) is not None, args)


def _count(receive: Any, args: argparse.Namespace) -> None:
    got, first, last = 0, 0.0, 0.0
    idle = 0
    while got < args.count:
        if not receive():
            idle += 1
            if got or idle * IDLE_S > 60:
                break
            continue
        last = time.perf_counter()
        if not got:
            first = last
        got += 1
    span = last - first
    rate = (got - 1) / span if got > 1 and span > 0 else 0.0
    print(json.dumps({"received": got, "sent": args.count, "msgs_per_s": rate,
                      "mb_per_s": rate * args.size / 1e6}), flush=True)


def ln_source(args: argparse.Namespace) -> None:
    import links_and_nodes as ln

    clnt = ln.client("bench_source")
    pub = clnt.publish(f"{args.name}.data", MDS[args.size], wait_for_subscribers=args.wait)
    while pub.subscriber_count < 1:
        time.sleep(0.01)
    time.sleep(0.5)  # the remote side's forwarding sets itself up
    for i in range(1, args.count + 1):
        pub.packet.counter = i
        pub.write(timeout=10.0)
    print(json.dumps({"sent": args.count}), flush=True)
    time.sleep(IDLE_S + 2)


# ---- plain Zenoh --------------------------------------------------------------------------------

def _session(args: argparse.Namespace) -> Any:
    import zenoh

    config = zenoh.Config()
    config.insert_json5("mode", '"peer"')
    config.insert_json5("scouting/multicast/enabled", "false")
    config.insert_json5("listen/endpoints", json.dumps([args.listen] if args.listen else []))
    if args.connect:
        config.insert_json5("connect/endpoints", json.dumps([args.connect]))
    return zenoh.open(config)


def z_pong(args: argparse.Namespace) -> None:
    import zenoh

    session = _session(args)
    pub = session.declare_publisher(f"{args.name}/pong", express=True,
                                    congestion_control=zenoh.CongestionControl.BLOCK)
    session.declare_subscriber(f"{args.name}/ping", lambda s: pub.put(s.payload.to_bytes()))
    print("ready", flush=True)
    threading.Event().wait()


def z_ping(args: argparse.Namespace) -> None:
    import zenoh

    session = _session(args)
    pub = session.declare_publisher(f"{args.name}/ping", express=True,
                                    congestion_control=zenoh.CongestionControl.BLOCK)
    sub = session.declare_subscriber(f"{args.name}/pong")
    while not pub.matching_status.matching:
        time.sleep(0.01)
    payload = bytearray(args.size)
    rtts: list[int] = []
    for i in range(1, args.count + args.warmup + 1):
        payload[:8] = i.to_bytes(8, "little")
        t0 = time.perf_counter_ns()
        pub.put(bytes(payload))
        while int.from_bytes(sub.recv().payload.to_bytes()[:8], "little") != i:
            pass
        if i > args.warmup:
            rtts.append(time.perf_counter_ns() - t0)
    print(json.dumps({**_stats(rtts), "resent": 0}), flush=True)
    session.close()


def z_sink(args: argparse.Namespace) -> None:
    import queue

    session = _session(args)
    arrivals: queue.SimpleQueue[None] = queue.SimpleQueue()
    session.declare_subscriber(f"{args.name}/data", lambda s: arrivals.put(None))
    print("ready", flush=True)

    def receive() -> bool:
        try:
            arrivals.get(timeout=IDLE_S)
        except queue.Empty:
            return False
        return True

    _count(receive, args)
    session.close()


def z_source(args: argparse.Namespace) -> None:
    import zenoh

    session = _session(args)
    pub = session.declare_publisher(f"{args.name}/data",
                                    congestion_control=zenoh.CongestionControl.BLOCK)
    while not pub.matching_status.matching:
        time.sleep(0.01)
    payload = bytes(args.size)
    for _ in range(args.count):
        pub.put(payload)
    print(json.dumps({"sent": args.count}), flush=True)
    time.sleep(IDLE_S + 2)
    session.close()


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("mode", choices=("ln-pong", "ln-ping", "ln-sink", "ln-source", "z-pong",
                                     "z-ping", "z-sink", "z-source"))
    ap.add_argument("size", type=int, choices=sorted(MDS))
    ap.add_argument("count", type=int, nargs="?", default=0)
    ap.add_argument("warmup", type=int, nargs="?", default=0)
    ap.add_argument("--name", default="bench", help="topic names NAME.ping, ... (keys NAME/...)")
    ap.add_argument("--transport", choices=("udp", "tcp"))
    ap.add_argument("--listen")
    ap.add_argument("--connect")
    ap.add_argument("--wait", action="store_true", help="ln-source: wait for subscribers")
    args = ap.parse_args()
    {"ln-pong": ln_pong, "ln-ping": ln_ping, "ln-sink": ln_sink, "ln-source": ln_source,
     "z-pong": z_pong, "z-ping": z_ping, "z-sink": z_sink, "z-source": z_source}[
        args.mode.replace("_", "-")](args)


if __name__ == "__main__":
    main()
