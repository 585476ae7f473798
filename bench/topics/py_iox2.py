"""iceoryx2 (PyPI `iceoryx2`) peer of `py_ln.py sub|pub ... zc|full` and `py_ln.py ping|pong
... full`: zero-copy throughput and ping-pong latency between two Python processes.  zc: the
publisher loans a sample and writes its first and last 8 bytes, the subscriber reads them;
full: a whole bytearray is copied into the loan and the received sample out whole (the echo:
into its own loan) with ctypes.memmove.  JSON lines and round-trip files as py_ln.py; see
bench_topics.py."""

from __future__ import annotations

import ctypes
import json
import os
import sys
import time
from array import array

import iceoryx2 as iox2
from payload import Payload
from receipts import Receipts, minflt

USAGE = """usage: py_iox2.py sub NAME SIZE COUNT BUFFERS WARM [zc|full]
       | pub NAME SIZE COUNT BUFFERS WARM SECONDS [zc|full]
       | pong NAME SIZE TOTAL WARMUP [zc|full] | ping NAME SIZE COUNT WARMUP OUT [zc|full]
A receiver polls (iceoryx2 publish-subscribe has no blocking receive; ping and pong yield
the CPU between polls) until the last sample or 2 s without one; publishers retry until
delivered (no loss).  ping writes COUNT round trips (ns) to OUT."""
U64 = ctypes.c_uint64


def payload_type(size: int) -> type[ctypes.Structure]:
    class Sample(ctypes.Structure):
        _fields_ = [("counter", ctypes.c_uint64), ("data", ctypes.c_uint8 * (size - 8))]

    Sample.__name__ = f"LnBenchSample{size}"
    return Sample


def open_service(name: str, size: int, buffers: int) -> tuple[iox2.Node, object]:
    iox2.set_log_level_from_env_or(iox2.LogLevel.Warn)
    node = iox2.NodeBuilder.new().create(iox2.ServiceType.Ipc)
    service = (node.service_builder(iox2.ServiceName.new(f"lnbench/{name}"))
               .publish_subscribe(payload_type(size))
               .enable_safe_overflow(False)
               .subscriber_max_buffer_size(buffers)
               .history_size(0)
               .max_publishers(1)
               .max_subscribers(1)
               .open_or_create())
    return node, service


def subscriber(name: str, size: int, count: int, buffers: int, warm: int, full: bool) -> None:
    _node, service = open_service(name, size, buffers)
    dst = Payload(size) if full else None
    sub = service.subscriber_builder().buffer_size(buffers).create()
    print("ready", flush=True)
    tally = Receipts(warm)
    now = time.perf_counter_ns
    idle_since = now()
    tail = size - 8
    while not tally.done(count):
        sample = sub.receive()
        if sample is None:
            if now() - idle_since > (2e9 if tally.received else 60e9):
                break
            continue
        addr = sample.payload_ptr
        if dst is not None:  # the whole sample out before it is released
            counter = end = dst.take(addr, "py_iox2")
        else:
            counter = U64.from_address(addr).value
            end = U64.from_address(addr + tail).value
        sample.delete()  # release it to the publisher
        if end != counter:
            sys.exit(f"py_iox2: torn sample {counter}/{end}")
        tally.got(counter)
        idle_since = tally.last_ns
    tally.report()


def open_publisher(service: object) -> object:
    return (service.publisher_builder()  # type: ignore[attr-defined]
            .backpressure_strategy(iox2.BackpressureStrategy.RetryUntilDelivered)
            .create())


def publisher(name: str, size: int, count: int, buffers: int, warm: int, seconds: float,
              full: bool) -> None:
    _node, service = open_service(name, size, buffers)
    pub = open_publisher(service)
    src = Payload(size) if full else None
    print("ready", flush=True)
    now = time.perf_counter_ns
    t0 = now()
    stop = t0 + int(seconds * 1e9) if seconds > 0 else None
    faults = minflt()
    sent = 0
    tail = size - 8
    for i in range(count):
        if i == warm:
            faults = minflt()
        last = stop is not None and (i & 15) == 0 and now() > stop
        counter = count - 1 if last else i
        sample = pub.loan_uninit()
        addr = sample.payload_ptr
        if src is not None:  # the whole sample from a bytearray into the loan
            src.stamp(counter)
            src.into(addr)
        else:
            U64.from_address(addr).value = counter
            U64.from_address(addr + tail).value = counter
        sample.assume_init().send()
        sent += 1
        if last:
            break
    elapsed = (now() - t0) * 1e-9
    print(json.dumps({"sent": sent, "elapsed_s": elapsed,
                      "minflt": minflt() - faults if sent > warm else 0,
                      "fault_samples": max(0, sent - warm)}))


class Ends:
    """Both ends of one side of the ping-pong: a publisher on NAME.ping (ping) or NAME.pong
    (pong) and a subscriber on the other; each service keeps one sample in flight."""

    def __init__(self, name: str, size: int, ping: bool) -> None:
        self.size = size
        self.nodes = []
        services = {}
        for way in ("ping", "pong"):
            node, services[way] = open_service(f"{name}.{way}", size, 1)
            self.nodes.append(node)
        out, inp = ("ping", "pong") if ping else ("pong", "ping")
        self.pub = open_publisher(services[out])
        self.sub = services[inp].subscriber_builder().buffer_size(1).create()

    def take(self) -> object:
        """The next sample, polling with sched_yield in between (as the Rust peer)."""
        receive, yield_cpu = self.sub.receive, os.sched_yield
        while (sample := receive()) is None:
            yield_cpu()
        return sample

    def send(self, src: Payload | None, value: int) -> None:
        sample = self.pub.loan_uninit()
        addr = sample.payload_ptr
        if src is not None:
            src.stamp(value)
            src.into(addr)
        else:
            U64.from_address(addr).value = value
            U64.from_address(addr + self.size - 8).value = value
        sample.assume_init().send()

    def receive(self, dst: Payload | None) -> int:
        sample = self.take()
        addr = sample.payload_ptr  # type: ignore[attr-defined]
        if dst is not None:
            value = dst.take(addr, "py_iox2")
        else:
            value = U64.from_address(addr).value
            if U64.from_address(addr + self.size - 8).value != value:
                sys.exit(f"py_iox2: torn sample {value}")
        sample.delete()  # type: ignore[attr-defined]
        return value

    def echo(self, full: bool) -> None:
        """Send the next sample back: (full) copied whole into a loan, else restamped."""
        sample = self.take()
        addr = sample.payload_ptr  # type: ignore[attr-defined]
        loan = self.pub.loan_uninit()
        if full:
            ctypes.memmove(loan.payload_ptr, addr, self.size)
        else:
            value = U64.from_address(addr).value
            U64.from_address(loan.payload_ptr).value = value
            U64.from_address(loan.payload_ptr + self.size - 8).value = value
        sample.delete()  # type: ignore[attr-defined]
        loan.assume_init().send()


def pong(name: str, size: int, total: int, warmup: int, full: bool) -> None:
    ends = Ends(name, size, ping=False)
    print("ready", flush=True)
    faults = minflt()
    for i in range(total):
        if i == warmup:
            faults = minflt()
        ends.echo(full)
    print(json.dumps({"minflt": minflt() - faults, "samples": max(0, total - warmup)}))


def ping(name: str, size: int, count: int, warmup: int, out: str, full: bool) -> None:
    ends = Ends(name, size, ping=True)
    src, dst = (Payload(size), Payload(size)) if full else (None, None)
    rtt = array("Q", bytes(8 * count))
    now = time.perf_counter_ns
    faults = 0
    for i in range(warmup + count):
        if i == warmup:
            faults = minflt()
        t0 = now()
        ends.send(src, i)
        back = ends.receive(dst)
        t1 = now()
        if back != i:
            sys.exit(f"py_iox2: round trip {i} came back as {back}")
        if i >= warmup:
            rtt[i - warmup] = t1 - t0
    print(json.dumps({"minflt": minflt() - faults, "samples": count}))
    with open(out, "wb") as f:
        rtt.tofile(f)


ARGC = {"sub": 7, "pub": 8, "pong": 6, "ping": 7}  # arguments before the optional mode


def main(argv: list[str]) -> int:
    role = argv[1] if len(argv) > 1 else ""
    full = argv[-1] == "full"
    args = argv[:-1] if argv[-1] in ("zc", "full") else argv
    if role not in ARGC or len(args) != ARGC[role]:
        print(USAGE, file=sys.stderr)
        return 2
    name, size, count = args[2], int(args[3]), int(args[4])
    if role == "pong":
        pong(name, size, count, int(args[5]), full)
    elif role == "ping":
        ping(name, size, count, int(args[5]), args[6], full)
    elif role == "sub":
        subscriber(name, size, count, int(args[5]), int(args[6]), full)
    else:
        publisher(name, size, count, int(args[5]), int(args[6]), float(args[7]), full)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
