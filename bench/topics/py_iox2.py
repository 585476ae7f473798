"""iceoryx2 (PyPI `iceoryx2`) peer of `py_ln.py sub|pub ... zc`: zero-copy throughput between
two Python processes, the publisher loaning a sample and writing its first and last 8 bytes,
the subscriber reading them.  Same arguments and JSON lines as py_ln.py; see bench_topics.py."""

from __future__ import annotations

import ctypes
import json
import sys
import time

import iceoryx2 as iox2
from receipts import Receipts, minflt

USAGE = """usage: py_iox2.py sub NAME SIZE COUNT BUFFERS WARM | pub NAME SIZE COUNT BUFFERS WARM SECONDS
The subscriber polls (iceoryx2 publish-subscribe has no blocking receive) until the last
sample or 2 s without one; the publisher retries until delivered (no loss)."""
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


def subscriber(name: str, size: int, count: int, buffers: int, warm: int) -> None:
    _node, service = open_service(name, size, buffers)
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
        counter = U64.from_address(addr).value
        end = U64.from_address(addr + tail).value
        sample.delete()  # release it to the publisher
        if end != counter:
            sys.exit(f"py_iox2: torn sample {counter}/{end}")
        tally.got(counter)
        idle_since = tally.last_ns
    tally.report()


def publisher(name: str, size: int, count: int, buffers: int, warm: int,
              seconds: float) -> None:
    _node, service = open_service(name, size, buffers)
    pub = (service.publisher_builder()
           .backpressure_strategy(iox2.BackpressureStrategy.RetryUntilDelivered)
           .create())
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


def main(argv: list[str]) -> int:
    if len(argv) < 7 or argv[1] not in ("sub", "pub") or (argv[1] == "pub" and len(argv) < 8):
        print(USAGE, file=sys.stderr)
        return 2
    name, size, count, buffers, warm = argv[2], int(argv[3]), int(argv[4]), int(argv[5]), int(argv[6])
    if argv[1] == "sub":
        subscriber(name, size, count, buffers, warm)
    else:
        publisher(name, size, count, buffers, warm, float(argv[7]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
