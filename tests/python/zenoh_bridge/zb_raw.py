"""Plain Zenoh sessions of the bridge tests (no links_and_nodes client), run inside a lab host:

    zb_raw.py bad KEY --connect EP           put malformed samples on KEY (a bridged topic key)
    zb_raw.py ros2 --connect EP [--count N]  print what --ros2 publishes as JSON lines
    zb_raw.py sub KEY --connect EP           print "got SEQ COUNTER" per sample of KEY
    zb_raw.py batches PREFIX TOPIC --connect EP   offer batches as bridge PREFIX would and put
                                             malformed ones, then good ones, on its batch key

`bad` waits until a subscriber matches KEY, puts one sample of each kind of damage, prints
"sent N" and exits.  `sub` prints "subscribed" first and "got" lines with the attachment's seq
and the sample's counter (zbtest/sample), "batch" for a sample whose payload is not a sample.
`batches` declares PREFIX/@live/batch, waits until a bridge subscribes to PREFIX/batch/TOPIC,
puts each kind of malformed batch, good batches of counters 1..3 and 4..5, one more malformed
one, a good one of 6..7, prints "sent N" (N malformed) and exits.  `ros2` prints {"token": KEY} per liveliness token under @ros2_lv/ and
{"key", "encoding", "payload" (hex), "seq", "time_ns", "gid"} per sample under <domain>/**.
"""

from __future__ import annotations

import argparse
import ctypes
import json
import queue
import struct
import sys
import time

import zenoh

from links_and_nodes.md_loader import message_class
from links_and_nodes.zenoh_bridge import ros2
from links_and_nodes.zenoh_bridge.wire import Attachment


def session(endpoint: str) -> zenoh.Session:
    """A client session through the bridge at `endpoint`: a peer routes for its clients (not
    for other peers, which it expects to reach the others themselves)."""
    config = zenoh.Config()
    config.insert_json5("mode", '"client"')
    config.insert_json5("scouting/multicast/enabled", "false")
    config.insert_json5("listen/endpoints", "[]")
    config.insert_json5("connect/endpoints", json.dumps([endpoint]))
    return zenoh.open(config)


def matched_publisher(s: zenoh.Session, key: str) -> zenoh.Publisher:
    """A publisher of `key` once a subscriber matches it (or after 30 s).  It blocks rather
    than drops: a large case must not be dropped by a full queue under load."""
    publisher = s.declare_publisher(key, congestion_control=zenoh.CongestionControl.BLOCK)
    deadline = time.monotonic() + 30
    while not publisher.matching_status.matching and time.monotonic() < deadline:
        time.sleep(0.02)
    return publisher


def bad(args: argparse.Namespace) -> None:
    cls = message_class("zbtest/sample")
    good = Attachment(7, time.time_ns(), cls.LAYOUT_HASH, "zbtest/sample").encode()
    other_hash = Attachment(8, time.time_ns(), cls.LAYOUT_HASH ^ 1, "zbtest/sample").encode()
    size = ctypes.sizeof(cls)
    cases: list[tuple[bytes, bytes | None]] = [
        (bytes(size), None),                                  # no attachment
        (bytes(size), b"\x01\x02\x03"),                      # too short
        (bytes(size), b"XX" + good[2:]),                      # wrong magic
        (bytes(size), good[:-3]),                             # md name cut short
        (bytes(size), good[:28] + b"\x02\xff\xfe"),           # md name not UTF-8
        (b"abc", good),                                        # wrong size
        (bytes(1 << 20), good),                                # far too big
        (bytes(size), other_hash),                             # another layout
    ]
    with session(args.connect) as s:
        publisher = matched_publisher(s, args.key)
        for payload, attachment in cases:
            publisher.put(payload, attachment=attachment)
        time.sleep(2.0)  # let the last puts leave before the session closes
        publisher.undeclare()
    print(f"sent {len(cases)}", flush=True)


def show_sub(args: argparse.Namespace) -> None:
    size = ctypes.sizeof(message_class("zbtest/sample"))

    def on_sample(sample: zenoh.Sample) -> None:
        payload = sample.payload.to_bytes()
        att = sample.attachment.to_bytes() if sample.attachment is not None else b""
        seq = struct.unpack_from("<Q", att, 4)[0] if len(att) >= 12 else -1
        if len(payload) != size:
            print(f"batch {seq}", flush=True)
            return
        print(f"got {seq} {struct.unpack_from('<Q', payload)[0]} OK", flush=True)

    with session(args.connect) as s:
        sub = s.declare_subscriber(args.key, on_sample)
        print("subscribed", flush=True)
        while True:
            time.sleep(3600)
        sub.undeclare()


def _batch(first: int, count: int) -> tuple[bytes, bytes]:
    """A batch of zbtest/sample counters first.. (seq = counter) and its attachment."""
    cls = message_class("zbtest/sample")
    body = b"LB\x01\x00" + struct.pack("<I", count)
    for counter in range(first, first + count):
        sample = cls()
        sample.counter, sample.value = counter, counter * 0.5
        data = bytes(sample)
        body += struct.pack("<QqI", counter, time.time_ns(), len(data)) + data
    return body, Attachment(first, time.time_ns(), cls.LAYOUT_HASH, "zbtest/sample").encode()


def batches(args: argparse.Namespace) -> None:
    good, att = _batch(1, 3)
    cases: list[tuple[bytes, bytes | None]] = [
        (b"XX" + good[2:], att),                                # wrong magic
        (good[:2] + b"\x09" + good[3:], att),                   # wrong version
        (good[:-1], att),                                      # cut short
        (good[:4] + struct.pack("<I", 1 << 30) + good[8:], att),  # count beyond the bytes
        (good + b"\x00", att),                                 # bytes after the samples
        (good, None),                                          # no attachment
    ]
    with session(args.connect) as s:
        token = s.liveliness().declare_token(f"{args.prefix}/@live/batch")
        publisher = matched_publisher(s, f"{args.prefix}/batch/{args.topic}")
        for payload, attachment in cases:
            publisher.put(payload, attachment=attachment)
        for first, count in ((1, 3), (4, 2)):
            payload, attachment = _batch(first, count)
            publisher.put(payload, attachment=attachment)
            time.sleep(0.5)  # the first sets the topic up at the receiving bridge
        publisher.put(cases[0][0], attachment=cases[0][1])  # the topic is set up: its counter
        payload, attachment = _batch(6, 2)
        publisher.put(payload, attachment=attachment)
        time.sleep(2.0)  # let the last puts leave before the session closes
        publisher.undeclare()
        token.undeclare()
    print(f"sent {len(cases) + 1}", flush=True)


def show_ros2(args: argparse.Namespace) -> None:
    events: queue.SimpleQueue[dict[str, object]] = queue.SimpleQueue()

    def on_sample(sample: zenoh.Sample) -> None:
        seq, t_ns, gid = ros2.decode_attachment(sample.attachment.to_bytes())
        events.put({"key": str(sample.key_expr), "encoding": str(sample.encoding),
                    "payload": sample.payload.to_bytes().hex(), "seq": seq,
                    "time_ns": t_ns, "gid": gid.hex()})

    with session(args.connect) as s:
        tokens = s.liveliness().declare_subscriber(
            f"@ros2_lv/{args.domain}/**",
            lambda sample: events.put({"token": str(sample.key_expr)}), history=True)
        sub = s.declare_subscriber(f"{args.domain}/**", on_sample)
        print("subscribed", flush=True)
        samples = 0
        while samples < args.count:
            event = events.get()
            samples += "key" in event
            print(json.dumps(event), flush=True)
        sub.undeclare()
        tokens.undeclare()


def main() -> None:
    ap = argparse.ArgumentParser()
    cmds = ap.add_subparsers(dest="cmd", required=True)
    p = cmds.add_parser("bad")
    p.add_argument("key")
    p.add_argument("--connect", required=True)
    p = cmds.add_parser("sub")
    p.add_argument("key")
    p.add_argument("--connect", required=True)
    p = cmds.add_parser("batches")
    p.add_argument("prefix")
    p.add_argument("topic")
    p.add_argument("--connect", required=True)
    p = cmds.add_parser("ros2")
    p.add_argument("--connect", required=True)
    p.add_argument("--domain", type=int, default=0)
    p.add_argument("--count", type=int, default=5)
    args = ap.parse_args()
    {"bad": bad, "ros2": show_ros2, "sub": show_sub, "batches": batches}[args.cmd](args)


if __name__ == "__main__":
    sys.exit(main())
