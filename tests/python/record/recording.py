"""Helpers of the recording tests: publishing numbered samples, reading a topic to its end,
the summary line ln_record ends with, and where a file's chunks are."""

from __future__ import annotations

import re
import signal
import struct
import subprocess
from pathlib import Path
from typing import Any

import links_and_nodes as ln

WAIT = 60.0  # seconds; only an upper bound for something that is expected to happen


def fill(msg: Any, i: int) -> Any:
    """Sample number `i` of rectest/sample (or rectest/tool): values derived from i."""
    msg.counter = i
    if hasattr(msg, "values"):
        msg.value = i * 0.25
        msg.values[:] = [i, -i, 2 * i, 5]
    else:
        msg.tcp.position[:] = [i, i + 1, i + 2]
        msg.when.sec = i
    return msg


def publish(pub: Any, numbers: range) -> None:
    for i in numbers:
        fill(pub.packet, i)
        pub.write(timeout=WAIT)


def read_all(sub: Any, count: int) -> list[tuple[int, dict[str, Any]]]:
    """(publish time, message as dict) of `count` samples (fails after WAIT without one)."""
    out = []
    while len(out) < count:
        pkt = sub.read(timeout=WAIT)
        assert pkt is not None, f"only {len(out)} of {count} samples came"
        out.append((sub.info.timestamp_ns, pkt.to_dict()))
    return out


def expected(md_name: str, numbers: range) -> list[dict[str, Any]]:
    cls = ln.message_class(md_name)
    return [fill(cls(), i).to_dict() for i in numbers]


def stop(proc: subprocess.Popen[bytes], signum: int = signal.SIGINT) -> int:
    proc.send_signal(signum)
    return proc.wait(timeout=WAIT)


SUMMARY = re.compile(r"ln_record: (\d+) samples \(.*\) of (\d+) topics, (\d+) dropped, in "
                     r"(\d+) files")


def summary(log: str) -> tuple[int, int, int, int]:
    """(samples, topics, dropped, files) of ln_record's last line."""
    found = SUMMARY.findall(log)
    assert found, f"no summary line in:\n{log}"
    samples, topics, dropped, files = map(int, found[-1])
    return samples, topics, dropped, files


def chunk_offsets(path: Path) -> list[tuple[int, int]]:
    """(offset, length with header) of every Chunk record, by walking the records."""
    data = path.read_bytes()
    at, out = 8, []
    while at + 9 <= len(data):
        opcode, length = struct.unpack_from("<BQ", data, at)
        if opcode == 6:
            out.append((at, 9 + length))
        if opcode == 2:
            break
        at += 9 + length
    return out
