"""Helpers of the replay control tests: a recording written directly with known times, an
ln_play started against the test's manager with its control service, and that service."""

from __future__ import annotations

import ctypes
import subprocess
import sys
import time
import uuid
from pathlib import Path
from typing import Any

from polling import wait_for

import links_and_nodes as ln
from links_and_nodes.mcap_format import McapWriter, md_schema_text

from .conftest import MD_DIR, Lab
from .recording import WAIT, fill

T0 = 1_700_000_000_000_000_000  # the first sample's publish time


def sample_times(n: int, step_ns: int) -> list[tuple[int, str, int]]:
    """(time, topic, counter) in play order: ctl.a's sample i at T0 + i*step, ctl.b's at
    T0 + i*step + step/2 for every fourth i."""
    out = []
    for i in range(n):
        out.append((T0 + i * step_ns, "ctl.a", i))
        if i % 4 == 0:
            out.append((T0 + i * step_ns + step_ns // 2, "ctl.b", i))
    return out


def write_recording(path: Path, n: int, step_ns: int) -> list[tuple[int, str, int]]:
    """A recording of sample_times(n, step_ns) (ctl.a: rectest/sample, ctl.b: rectest/tool),
    the samples of ctl.b written a little late, as a recorder reads them; its samples."""
    md = {"ctl.a": "rectest/sample", "ctl.b": "rectest/tool"}
    order = sample_times(n, step_ns)
    with McapWriter(path, compression="none", chunk_size=4096) as w:
        channels = {}
        for topic, md_name in md.items():
            cls = ln.message_class(md_name)
            channels[topic] = w.add_topic(topic, md_name, md_schema_text(md_name, [str(MD_DIR)]),
                                          cls.LAYOUT_HASH, ctypes.sizeof(cls))
        seqs = {"ctl.a": 0, "ctl.b": 0}
        held: list[tuple[int, str, int]] = []
        for item in order:
            if item[1] == "ctl.b":  # written after the next ctl.a: the reordering window's job
                held.append(item)
                continue
            _write(w, channels, seqs, md, item)
            for late in held:
                _write(w, channels, seqs, md, late)
            held.clear()
        for late in held:
            _write(w, channels, seqs, md, late)
    return order


def _write(w: McapWriter, channels: dict[str, int], seqs: dict[str, int], md: dict[str, str],
           item: tuple[int, str, int]) -> None:
    t, topic, i = item
    seqs[topic] += 1
    w.write(channels[topic], seqs[topic], t, bytes(fill(ln.message_class(md[topic])(), i)))


def start_player(lab: Lab, path: Path, *args: str, log: str = "play.log",
                 **popen: Any) -> tuple[subprocess.Popen[bytes], str]:
    """ln_play PATH with a unique control service (its name returned) and ARGS."""
    name = f"play_{uuid.uuid4().hex[:8]}.control"
    popen.setdefault("stdin", subprocess.DEVNULL)
    if "stderr" not in popen:
        popen["stderr"] = open(lab.tmp / log, "wb")  # noqa: SIM115 - the child keeps it
    proc = subprocess.Popen(
        [sys.executable, "-m", "links_and_nodes.record.play_cli", "--md-dir", str(MD_DIR),
         "--control-service", name, *args, str(path)],
        stdout=subprocess.DEVNULL, env=lab.env(), **popen)
    lab.procs.append(proc)
    return proc, name


class Control:
    """A caller of ln_play's control service (md ln/player)."""

    def __init__(self, clnt: Any, name: str) -> None:
        self.svc = clnt.get_service(name, "ln/player")
        wait_for(self._reachable, f"the control service {name}")

    def _reachable(self) -> bool:
        try:
            self("status")
        except ln.LnError:
            return False
        return True

    def __call__(self, command: str, time_ns: int = 0, relative: bool = False,
                 rate: float = 0.0) -> Any:
        req = self.svc.req
        req.command = command
        req.time_ns = time_ns
        req.relative = int(relative)
        req.rate = rate
        self.svc.call(timeout=WAIT)
        return self.svc.resp


def subscribe(clnt: Any) -> dict[str, Any]:
    """Queued subscribers of both topics, large enough to lose nothing."""
    return {"ctl.a": clnt.subscribe("ctl.a", "rectest/sample", buffers=1024),
            "ctl.b": clnt.subscribe("ctl.b", "rectest/tool", buffers=1024)}


class Played:
    """What the subscribers received, in the order it was played (by the new publish times
    of the one player thread).  take(n) gives the next n: it reads until it has n, then
    everything already waiting, so that whatever was played before the n-th is among them."""

    def __init__(self, subs: dict[str, Any]) -> None:
        self.subs = subs
        self._buffer: list[tuple[int, str, int]] = []

    def _read(self, timeout: float) -> int:
        n = 0
        for topic, sub in self.subs.items():
            while (pkt := sub.read(timeout=timeout)) is not None:
                self._buffer.append((sub.info.timestamp_ns, topic, int(pkt.counter)))
                n += 1
                timeout = 0
        return n

    def take(self, count: int) -> list[tuple[str, int]]:
        """The next `count` samples as (topic, counter)."""
        deadline = time.monotonic() + WAIT
        while len(self._buffer) < count:
            assert time.monotonic() < deadline, (
                f"only {len(self._buffer)} of {count} samples came: {self._buffer}")
            self._read(0.01)
        self._read(0)
        self._buffer.sort()
        out, self._buffer = self._buffer[:count], self._buffer[count:]
        return [(topic, i) for _, topic, i in out]

    def nothing_more(self) -> bool:
        """No sample is left: none taken, none waiting."""
        return not self._buffer and self._read(0) == 0
