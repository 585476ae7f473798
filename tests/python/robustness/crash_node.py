"""One process of the crash-injection driver's synthetic system (crash_driver.py): a publisher,
subscriber, service provider or caller that checks every sample and response it sees and
reports a heartbeat, its progress and any violation as files in a report directory.

    python crash_node.py ROLE NAME REPORT_DIR MD_DIR ITEM[,ITEM...] [--mode M]

Every sample of lntest/pattern holds value V = MAGIC | pid | counter in word 0 and
V ^ KEY[i] in word i, so a torn (partly written or overwritten) sample is always visible.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

import links_and_nodes as ln

MAGIC = 0xC0DE << 48
KEY = (np.arange(512, dtype=np.uint64) * np.uint64(0x9E3779B97F4A7C15)).astype(np.uint64)
READ_TIMEOUT = 0.1  # seconds a subscriber's read or borrow may wait
CALL_TIMEOUT = 1.0  # seconds a service call may take
SLACK = 2.0  # seconds over its timeout after which an operation counts as hung


class Reporter:
    """The files the driver reads: NAME.hb (JSON, replaced atomically: pid, time, counts),
    NAME.violations (a line per violation), NAME.calls (a line per service call) and
    NAME.busy (exists while the process sleeps inside a loan, borrow or handler)."""

    def __init__(self, directory: Path, name: str) -> None:
        self.base = directory / name
        self.pid = os.getpid()
        self.counts: dict[str, dict[str, float]] = {}
        self.last_hb = 0.0
        self.violations = open(f"{self.base}.violations", "a", buffering=1)  # noqa: SIM115
        self.calls = open(f"{self.base}.calls", "a", buffering=1)  # noqa: SIM115

    def count(self, item: str, what: str, n: float = 1) -> None:
        entry = self.counts.setdefault(item, {})
        entry[what] = entry.get(what, 0) + n

    def violation(self, text: str) -> None:
        self.violations.write(f"{time.time():.3f} pid {self.pid}: {text}\n")

    def heartbeat(self, force: bool = False) -> None:
        now = time.time()
        if not force and now - self.last_hb < 0.1:
            return
        self.last_hb = now
        tmp = f"{self.base}.hb.{self.pid}"
        with open(tmp, "w") as f:
            json.dump({"pid": self.pid, "time": now, "counts": self.counts}, f)
        os.replace(tmp, f"{self.base}.hb")

    def busy(self, on: bool) -> None:
        path = Path(f"{self.base}.busy")
        if on:
            path.write_text(str(self.pid))
        else:
            path.unlink(missing_ok=True)


def check_pattern(words: Any) -> int | None:
    """The sample's value V if every word matches it, else None."""
    value = int(words[0])
    if value >> 48 != MAGIC >> 48:
        return None
    if not np.array_equal(words, np.uint64(value) ^ KEY):
        return None
    return value


def timed(rep: Reporter, what: str, limit: float, start: float) -> None:
    took = time.monotonic() - start
    if took > limit + SLACK:
        rep.violation(f"hang: {what} took {took:.2f} s (limit {limit} s)")


def publisher(clnt: ln.client, rep: Reporter, topics: list[str], mode: str) -> None:
    """mode copy: write(); loan: zero-copy, now and then half-filled and asleep in the loan."""
    pubs = [clnt.publish(t, "lntest/pattern") for t in topics]
    rng = random.Random(rep.pid)
    counter = 0
    base = MAGIC | ((rep.pid & 0xFFFFFF) << 24)
    print("ready", flush=True)
    while True:
        for topic, pub in zip(topics, pubs, strict=True):
            counter = (counter + 1) & 0xFFFFFF
            value = np.uint64(base | counter)
            start = time.monotonic()
            if mode == "loan":
                with pub.loan(timeout=1.0) as msg:
                    if rng.random() < 0.2:  # torn on purpose, if we die in here
                        rep.busy(True)
                        msg.word[:256] = value ^ KEY[:256]
                        time.sleep(rng.uniform(0.02, 0.15))
                        msg.word[256:] = value ^ KEY[256:]
                        rep.busy(False)
                    else:
                        msg.word[:] = value ^ KEY
            else:
                pub.packet.word[:] = value ^ KEY
                pub.write(timeout=1.0)
            timed(rep, f"write {topic}", 1.0 + 0.15, start)
            rep.count(topic, "sent")
            rep.heartbeat()
        time.sleep(0.01)


def subscriber(clnt: ln.client, rep: Reporter, topics: list[str], mode: str) -> None:
    """mode latest / queued: read() into a copy; borrow: zero-copy, now and then asleep in
    the borrow (queued, 8 buffers)."""
    buffers = 1 if mode == "latest" else 8
    subs = [clnt.subscribe(t, "lntest/pattern", buffers=buffers) for t in topics]
    rng = random.Random(rep.pid)
    last: dict[tuple[str, int], int] = {}
    print("ready", flush=True)

    def seen(topic: str, value: int | None, words: Any) -> None:
        if value is None:
            rep.violation(f"torn sample on {topic}: words[0..3] = "
                          f"{[hex(int(w)) for w in words[:4]]}")
            return
        key = (topic, (value >> 24) & 0xFFFFFF)
        counter = value & 0xFFFFFF
        if key in last and counter < last[key] and last[key] - counter < 0x800000:
            rep.violation(f"sample of {topic} from pid {key[1]} went back: {counter} after "
                          f"{last[key]}")
        last[key] = counter
        rep.count(topic, "good")

    while True:
        for topic, sub in zip(topics, subs, strict=True):
            start = time.monotonic()
            if mode == "borrow":
                try:
                    with sub.borrow(timeout=READ_TIMEOUT) as msg:
                        if msg is not None:
                            words = np.array(msg.word)  # a copy taken while borrowed
                            if rng.random() < 0.1:
                                rep.busy(True)
                                time.sleep(rng.uniform(0.02, 0.1))
                                rep.busy(False)
                            value = check_pattern(words)
                except ln.LnOverrunError:
                    rep.count(topic, "overrun")  # overwritten meanwhile: discarded
                else:
                    if msg is not None:
                        seen(topic, value, words)
            else:
                pkt = sub.read(timeout=READ_TIMEOUT)
                if pkt is not None:
                    seen(topic, check_pattern(pkt.word), pkt.word)
            timed(rep, f"read {topic}", READ_TIMEOUT, start)
            rep.heartbeat()


def provider(clnt: ln.client, rep: Reporter, services: list[str], mode: str) -> None:
    """Echoes each request after sleeping its delay_us (so a kill can land mid-call)."""

    def handler(request: Any) -> None:
        delay = request.req.delay_us / 1e6
        if delay:
            rep.busy(True)
            time.sleep(delay)
            rep.busy(False)
        request.respond({"caller": request.req.caller, "seq": request.req.seq,
                         "text": request.req.text})
        rep.count(request.service_name, "served")

    for name in services:
        clnt.get_service_provider(name, "lntest/echo", handler)
    print("ready", flush=True)
    while True:
        clnt.wait_and_handle_service_group_requests(None, 0.1)
        rep.heartbeat()


def caller(clnt: ln.client, rep: Reporter, services: list[str], mode: str) -> None:
    """Calls each service in turn, a fifth of the calls with a slow handler; checks that
    each response echoes its own request and that no call outlasts its timeout."""
    svcs = [clnt.get_service(name, "lntest/echo") for name in services]
    rng = random.Random(rep.pid)
    seq = 0
    print("ready", flush=True)
    while True:
        for name, svc in zip(services, svcs, strict=True):
            seq += 1
            svc.req.caller = rep.pid & 0xFFFFFFFF
            svc.req.seq = seq
            svc.req.delay_us = rng.randrange(50_000, 300_000) if rng.random() < 0.2 else 0
            svc.req.text = f"{name}:{seq}"
            start = time.monotonic()
            try:
                resp = svc.call(timeout=CALL_TIMEOUT)
            except ln.LnError as exc:
                outcome = f"error {type(exc).__name__}"
                rep.count(name, "error")
            else:
                if (resp.caller, resp.seq, resp.text) != (rep.pid & 0xFFFFFFFF, seq,
                                                          f"{name}:{seq}"):
                    rep.violation(f"{name}: response {resp.caller}/{resp.seq}/{resp.text!r} "
                                  f"to request {rep.pid}/{seq}")
                outcome = "ok"
                rep.count(name, "ok")
            took = time.monotonic() - start
            rep.calls.write(f"{time.time():.3f} {name} {outcome} {took:.4f}\n")
            timed(rep, f"call {name}", CALL_TIMEOUT, start)
            rep.heartbeat()
        time.sleep(0.02)


ROLES = {"pub": publisher, "sub": subscriber, "provider": provider, "caller": caller}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("role", choices=sorted(ROLES))
    parser.add_argument("name")
    parser.add_argument("report_dir", type=Path)
    parser.add_argument("md_dir", help="message definition directories, os.pathsep between")
    parser.add_argument("items", help="topics or services, comma-separated")
    parser.add_argument("--mode", default="")
    args = parser.parse_args(argv)
    for directory in args.md_dir.split(os.pathsep):
        ln.add_message_definition_dir(directory)
    rep = Reporter(args.report_dir, args.name)
    rep.heartbeat(force=True)
    clnt = ln.client(args.name, timeout=2.0)
    ROLES[args.role](clnt, rep, args.items.split(","), args.mode)
    return 0


if __name__ == "__main__":
    sys.exit(main())
