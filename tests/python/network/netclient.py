"""The programs of the multi-host tests, run as .lnc processes on the lab's hosts:

    netclient.py pub TOPIC MD --count N --rate HZ      publish counters 1..N (0: forever)
    netclient.py sub TOPIC MD [--transport udp|tcp] [--buffers N]
                                                      print "got SEQ COUNTER OK" per sample
    netclient.py provide SERVICE                      provide nettest/echo
    netclient.py call SERVICE --count N               call it, print "call I OK|FAIL ..."
    netclient.py watch TOPIC MD [--transport udp|tcp]  a waitset on a subscriber: "back",
                                                      "got SEQ COUNTER OK", "gone" per event

Samples carry a counter; 8 MiB blobs a byte pattern derived from it, which the subscriber
checks completely.  Output lines are what the tests read through the manager."""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

import links_and_nodes as ln


def pattern(counter: int, size: int) -> np.ndarray:
    return ((np.arange(size, dtype=np.uint32) * 7 + counter) & 0xFF).astype(np.uint8)


def publish(clnt: ln.client, args: argparse.Namespace) -> None:
    pub = clnt.publish(args.topic, args.md)
    period = 1.0 / args.rate if args.rate > 0 else 0.0
    counter = 0
    print("publishing", flush=True)
    while args.count == 0 or counter < args.count:
        counter += 1
        pub.packet.counter = counter
        if hasattr(pub.packet, "data"):
            pub.packet.data[:] = pattern(counter, len(pub.packet.data))
        else:
            pub.packet.value = counter * 0.5
        pub.write()
        if period:
            time.sleep(period)
    print(f"published {counter}", flush=True)
    time.sleep(3600)  # stay: the topic keeps its publisher


def subscribe(clnt: ln.client, args: argparse.Namespace) -> None:
    sub = clnt.subscribe(args.topic, args.md, buffers=args.buffers, transport=args.transport)
    print("subscribed", flush=True)
    while True:
        packet = sub.read(timeout=1.0)
        if packet is None:
            continue
        if hasattr(packet, "data"):
            ok = bool(np.array_equal(np.asarray(packet.data),
                                     pattern(packet.counter, len(packet.data))))
        else:
            ok = packet.value == packet.counter * 0.5
        print(f"got {sub.info.seq} {packet.counter} {'OK' if ok else 'BAD'}", flush=True)


def provide(clnt: ln.client, args: argparse.Namespace) -> None:
    def handler(request: ln.service_request) -> None:
        req, resp = request.req, request.resp
        resp.text = req.text.upper()
        resp.values = [v * 2 for v in req.values]
        resp.count = len(req.words)
        request.respond()

    clnt.get_service_provider(args.service, "nettest/echo", handler)
    print("providing", flush=True)
    while True:
        clnt.wait_and_handle_service_group_requests(None, 1.0)


def call(clnt: ln.client, args: argparse.Namespace) -> None:
    svc = clnt.get_service(args.service, "nettest/echo")
    for i in range(args.count):
        svc.req.text = f"hello {i}"
        svc.req.values = [float(i), 1.5]
        svc.req.words = [{"data": w} for w in ("a", "bb", "ccc")[:i % 3 + 1]]
        try:
            svc.call(timeout=5.0)
        except ln.LnError as exc:
            print(f"call {i} FAIL {exc}", flush=True)
            continue
        ok = (svc.resp.text == f"HELLO {i}" and list(svc.resp.values) == [2.0 * i, 3.0]
              and svc.resp.count == i % 3 + 1)
        print(f"call {i} {'OK' if ok else 'BAD'} {svc.resp.text!r}", flush=True)
    print("calls done", flush=True)
    time.sleep(3600)


def watch(clnt: ln.client, args: argparse.Namespace) -> None:
    sub = clnt.subscribe(args.topic, args.md, buffers=16, transport=args.transport)
    with ln.WaitSet() as ws:
        ws.attach_subscriber(sub, liveliness=True)
        print("watching", flush=True)
        while True:
            for event in ws.wait():
                if event.kind == ln.WaitKind.DATA:
                    while (packet := sub.read(timeout=0)) is not None:
                        print(f"got {sub.info.seq} {packet.counter} OK", flush=True)
                else:
                    print(event.kind.name.lower(), flush=True)


def main() -> None:
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers(dest="mode", required=True)
    p = sub.add_parser("pub")
    p.add_argument("topic")
    p.add_argument("md")
    p.add_argument("--count", type=int, default=0)
    p.add_argument("--rate", type=float, default=100.0)
    s = sub.add_parser("sub")
    s.add_argument("topic")
    s.add_argument("md")
    s.add_argument("--transport", choices=("udp", "tcp"))
    s.add_argument("--buffers", type=int, default=1)
    v = sub.add_parser("provide")
    v.add_argument("service")
    c = sub.add_parser("call")
    c.add_argument("service")
    c.add_argument("--count", type=int, default=10)
    w = sub.add_parser("watch")
    w.add_argument("topic")
    w.add_argument("md")
    w.add_argument("--transport", choices=("udp", "tcp"))
    args = parser.parse_args()
    clnt = ln.client(f"net-{args.mode}")
    {"pub": publish, "sub": subscribe, "provide": provide, "call": call,
     "watch": watch}[args.mode](clnt, args)


if __name__ == "__main__":
    sys.exit(main())
