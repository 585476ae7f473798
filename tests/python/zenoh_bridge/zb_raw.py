"""Plain Zenoh sessions of the bridge tests (no links_and_nodes client), run inside a lab host:

    zb_raw.py bad KEY --connect EP           put malformed samples on KEY (a bridged topic key)
    zb_raw.py ros2 --connect EP [--count N]  print what --ros2 publishes as JSON lines

`bad` waits until a subscriber matches KEY, puts one sample of each kind of damage, prints
"sent N" and exits.  `ros2` prints {"token": KEY} per liveliness token under @ros2_lv/ and
{"key", "encoding", "payload" (hex), "seq", "time_ns", "gid"} per sample under <domain>/**.
"""

from __future__ import annotations

import argparse
import ctypes
import json
import queue
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
        # block, not drop: the 1 MiB case must not be dropped by a full queue under load
        publisher = s.declare_publisher(args.key,
                                        congestion_control=zenoh.CongestionControl.BLOCK)
        deadline = time.monotonic() + 30
        while not publisher.matching_status.matching and time.monotonic() < deadline:
            time.sleep(0.02)
        for payload, attachment in cases:
            publisher.put(payload, attachment=attachment)
        time.sleep(2.0)  # let the last puts leave before the session closes
        publisher.undeclare()
    print(f"sent {len(cases)}", flush=True)


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
    p = cmds.add_parser("ros2")
    p.add_argument("--connect", required=True)
    p.add_argument("--domain", type=int, default=0)
    p.add_argument("--count", type=int, default=5)
    args = ap.parse_args()
    {"bad": bad, "ros2": show_ros2}[args.cmd](args)


if __name__ == "__main__":
    sys.exit(main())
