"""Python side of the service benchmark over links_and_nodes: the roles of svc_ln.c with the
same arguments and output, written as a user would (svc.req.data = ...; svc.call();
request.respond()).  The manager comes from $LN_MANAGER.  See bench_services.py."""

from __future__ import annotations

import os
import struct
import sys
import time
from array import array
from pathlib import Path
from typing import Any

import links_and_nodes as ln

MD_DIR = Path(__file__).resolve().parent / "md"
MD = "bench/echo64"
USAGE = """usage: py_svc_ln.py provide NAME TOTAL | call NAME COUNT WARMUP OUT"""
COUNTER = struct.Struct("<Q")
IDLE_LIMIT = 60  # seconds without any call before the provider gives up


def provide(clnt: ln.client, name: str, total: int) -> None:
    def echo(request: Any) -> None:
        request.resp.data = request.req.data
        request.respond()

    clnt.get_service_provider(name, MD, echo)
    print("ready", flush=True)
    handled = idle = 0
    while handled < total:
        got = clnt.wait_and_handle_service_group_requests(None, 1.0)
        handled += got
        idle = 0 if got else idle + 1
        if idle >= IDLE_LIMIT:
            sys.exit(f"py_svc_ln: no call for {IDLE_LIMIT} s after {handled} of {total}")


def call(clnt: ln.client, name: str, count: int, warmup: int, out: str) -> None:
    svc = clnt.get_service(name, MD)
    buf = bytearray(b"\x5a" * 64)
    rtt = array("Q", bytes(8 * count))
    now, pack, unpack = time.perf_counter_ns, COUNTER.pack_into, COUNTER.unpack_from
    for i in range(warmup + count):
        t0 = now()
        pack(buf, 0, i)
        svc.req.data = buf
        svc.call(10.0)
        got = unpack(svc.resp.data)[0]
        t1 = now()
        if got != i:
            sys.exit(f"py_svc_ln: call {i} came back as {got}")
        if i >= warmup:
            rtt[i - warmup] = t1 - t0
    with open(out, "wb") as f:
        rtt.tofile(f)


def main(argv: list[str]) -> int:
    if not ((len(argv) == 4 and argv[1] == "provide") or (len(argv) == 6 and argv[1] == "call")):
        print(USAGE, file=sys.stderr)
        return 2
    ln.add_message_definition_dir(MD_DIR)
    with ln.client(f"py_svc_ln_{argv[1]}", os.environ["LN_MANAGER"]) as clnt:
        if argv[1] == "provide":
            provide(clnt, argv[2], int(argv[3]))
        else:
            call(clnt, argv[2], int(argv[3]), int(argv[4]), argv[5])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
