"""links_and_nodes clients of the Zenoh bridge tests, run as programs inside a site (a lab host):

    zb_peer.py pub TOPIC MD [--count N] [--rate HZ]   publish counter 1..N (0: forever),
               [--wait-subscribers N] [--wait]    once N subscribers are there (--wait: a
                                                  publisher that waits for their buffers)
    zb_peer.py sub TOPIC MD [--buffers N] [--stall]   print "got SEQ COUNTER" per sample
                                                      (--stall: subscribe, never read)
    zb_peer.py provide NAME                           provide zbtest/echo
    zb_peer.py call NAME TEXT [--deadline S]          call zbtest/echo until it is there

The manager is $LN_MANAGER; md directories come from $LN_MESSAGE_DEFINITION_DIRS.  Output is
line-buffered so the tests can follow it.
"""

from __future__ import annotations

import argparse
import sys
import time

import links_and_nodes as ln


def pub(args: argparse.Namespace) -> None:
    clnt = ln.client(f"zb_pub_{args.topic}")
    port = clnt.publish(args.topic, args.md, wait_for_subscribers=args.wait)
    while port.subscriber_count < args.wait_subscribers:
        time.sleep(0.01)
    print("publishing", flush=True)
    period = 1.0 / args.rate if args.rate else 0.0
    start = time.monotonic()
    i = 0
    while args.count == 0 or i < args.count:
        i += 1
        port.packet.counter = i
        if hasattr(port.packet, "value"):
            port.packet.value = i * 0.5
        port.write(timeout=60.0)
        if period:
            time.sleep(max(0.0, start + i * period - time.monotonic()))
    print(f"published {i}", flush=True)
    time.sleep(args.linger)


def sub(args: argparse.Namespace) -> None:
    clnt = ln.client(f"zb_sub_{args.topic}" + ("_stalled" if args.stall else ""))
    port = clnt.subscribe(args.topic, args.md, buffers=args.buffers)
    print("subscribed", flush=True)
    while args.stall:
        time.sleep(3600)
    while True:
        msg = port.read(timeout=1.0)
        if msg is not None:
            ok = "BAD" if getattr(msg, "value", msg.counter * 0.5) != msg.counter * 0.5 else "OK"
            print(f"got {port.info.seq} {msg.counter} {ok}", flush=True)


def provide(args: argparse.Namespace) -> None:
    clnt = ln.client("zb_provider")

    def handler(request: ln.service_request) -> None:
        req = request.req
        if req.text == "fail":
            request.respond_error("asked to fail")
            return
        words = [w["data"] for w in req.to_dict()["words"]]
        request.respond({"text": req.text.upper(), "values": [v * req.scale for v in req.values],
                         "count": len(words), "words": [{"data": w[::-1]} for w in words]})

    clnt.get_service_provider(args.name, "zbtest/echo", handler)
    print("providing", flush=True)
    while True:
        clnt.wait_and_handle_service_group_requests(None, 1.0)


def call(args: argparse.Namespace) -> None:
    clnt = ln.client("zb_caller")
    svc = clnt.get_service(args.name, "zbtest/echo")
    svc.req.text = args.text
    svc.req.values = [1.5, -2.0, 1e300]
    svc.req.words = [{"data": "alpha"}, {"data": "beta"}, {"data": "ü∑"}]
    svc.req.scale = 3
    deadline = time.monotonic() + args.deadline
    while True:
        try:
            resp = svc.call(timeout=10.0)
        except ln.LnError as exc:
            if type(exc).__name__ == "LnNotfoundError" and time.monotonic() < deadline:
                time.sleep(0.1)
                continue
            print(f"call ERROR {type(exc).__name__}: {exc}", flush=True)
            return
        print(f"call OK {resp.to_dict()!r}", flush=True)
        return


def main() -> None:
    ap = argparse.ArgumentParser()
    sub_parsers = ap.add_subparsers(dest="cmd", required=True)
    p = sub_parsers.add_parser("pub")
    p.add_argument("topic")
    p.add_argument("md")
    p.add_argument("--count", type=int, default=0)
    p.add_argument("--rate", type=float, default=0.0)
    p.add_argument("--linger", type=float, default=3600.0)
    p.add_argument("--wait-subscribers", type=int, default=0)
    p.add_argument("--wait", action="store_true")
    p = sub_parsers.add_parser("sub")
    p.add_argument("topic")
    p.add_argument("md")
    p.add_argument("--buffers", type=int, default=1)
    p.add_argument("--stall", action="store_true")
    p = sub_parsers.add_parser("provide")
    p.add_argument("name")
    p = sub_parsers.add_parser("call")
    p.add_argument("name")
    p.add_argument("text")
    p.add_argument("--deadline", type=float, default=30.0)
    args = ap.parse_args()
    {"pub": pub, "sub": sub, "provide": provide, "call": call}[args.cmd](args)


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:
        sys.exit(0)
