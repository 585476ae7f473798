"""`ln_bag info`: what a recording holds, per topic and service channel.

Read: the summary (Statistics, Chunk Indexes) when the file has one, else the chunk headers,
for chunk count, compressions and the summary's own counts; then one streaming pass over
every sample for what only the samples tell: per channel count, bytes, time range and gaps
(sequence numbers missing between consecutive samples)."""

from __future__ import annotations

import argparse
import json
import os
import sys
from dataclasses import asdict, dataclass
from datetime import UTC, datetime
from typing import Any

from ..mcap_format import McapTruncatedError, TopicInfo
from .errors import BagError
from .progress import Progress
from .source import Source
from .summary import read_layout

HELP = "per topic: md, layout hash, encoding, count, rate, times, bytes, gaps"


def add_arguments(ap: argparse.ArgumentParser) -> None:
    ap.add_argument("--json", action="store_true", help="print JSON instead of a table")


@dataclass
class ChannelStats:
    """One channel's figures from the streaming pass."""

    topic: str
    kind: str
    md_name: str
    layout_hash: str
    message_encoding: str
    count: int = 0
    bytes: int = 0
    first_ns: int | None = None
    last_ns: int | None = None
    gaps: int = 0  # sequence numbers missing between consecutive samples
    seq_resets: int = 0  # samples whose seq is not above the one before
    _last_seq: int | None = None

    @property
    def rate_hz(self) -> float | None:
        if self.count < 2 or not self.last_ns or self.last_ns == self.first_ns:
            return None
        return (self.count - 1) * 1e9 / (self.last_ns - (self.first_ns or 0))

    def add(self, seq: int, t: int, size: int) -> None:
        self.count += 1
        self.bytes += size
        self.first_ns = t if self.first_ns is None else min(self.first_ns, t)
        self.last_ns = t if self.last_ns is None else max(self.last_ns, t)
        prev = self._last_seq
        if prev is not None:
            if seq > prev + 1:
                self.gaps += seq - prev - 1
            elif seq <= prev:
                self.seq_resets += 1
        self._last_seq = seq

    def as_dict(self) -> dict[str, Any]:
        d = {k: v for k, v in asdict(self).items() if not k.startswith("_")}
        d["rate_hz"] = self.rate_hz
        return d


def _status(src: Source) -> str:
    if src.error is None:
        return "complete" if src.reader.complete else "no summary (not closed)"
    cut = "cut short" if isinstance(src.error, McapTruncatedError) else "corrupt"
    return f"{cut}: {src.error}"


def file_info(path: str, quiet: bool = True) -> dict[str, Any]:
    """Everything `info` says about one file."""
    layout = read_layout(path)
    src = Source(path)
    stats: dict[int, ChannelStats] = {}
    progress = Progress(f"ln_bag info {path}", layout.message_count, enabled=False if quiet
                        else None)
    for info, s in src:
        st = stats.get(id(info))
        if st is None:
            st = stats[id(info)] = _new(info)
        st.add(s.seq, s.publish_time_ns, len(s.data))
        progress.add(len(s.data))
    progress.done()
    channels = [st.as_dict() for st in stats.values()]
    firsts = [c["first_ns"] for c in channels if c["first_ns"] is not None]
    lasts = [c["last_ns"] for c in channels if c["last_ns"] is not None]
    return {
        "path": path, "size": os.path.getsize(path), "status": _status(src),
        "complete": src.complete, "summary": layout.summary,
        "error": None if src.error is None else {"offset": src.error.offset,
                                                  "what": src.error.what},
        "summary_message_count": layout.message_count, "chunks": layout.chunk_count,
        "compressions": dict(layout.compressions),
        "messages": sum(c["count"] for c in channels),
        "first_ns": min(firsts) if firsts else None, "last_ns": max(lasts) if lasts else None,
        "topics": [c for c in channels if c["kind"] != "service"],
        "services": [c for c in channels if c["kind"] == "service"],
    }


def _new(info: TopicInfo) -> ChannelStats:
    return ChannelStats(info.topic, info.kind, info.md_name, f"{info.layout_hash:016x}",
                        info.message_encoding)


def _time(ns: int | None) -> str:
    if ns is None:
        return "-"
    stamp = datetime.fromtimestamp(ns // 1_000_000_000, UTC).strftime("%Y-%m-%dT%H:%M:%S")
    return f"{stamp}.{ns % 1_000_000_000:09d}Z"


def _print(d: dict[str, Any]) -> None:
    comp = ", ".join(f"{k} {v}" for k, v in sorted(d["compressions"].items())) or "-"
    span = ((d["last_ns"] - d["first_ns"]) / 1e9) if d["first_ns"] is not None else 0.0
    print(f"{d['path']}: {d['size']} bytes, {d['status']}")
    print(f"  {d['messages']} samples, {d['chunks']} chunks ({comp}), "
          f"{_time(d['first_ns'])} .. {_time(d['last_ns'])} ({span:.3f} s)")
    if d["summary_message_count"] is not None and d["summary_message_count"] != d["messages"]:
        print(f"  note: the summary says {d['summary_message_count']} samples")
    for title, rows in (("topics", d["topics"]), ("services", d["services"])):
        if not rows:
            continue
        print(f"  {title}:")
        for c in rows:
            rate = f"{c['rate_hz']:.1f} Hz" if c["rate_hz"] else "-"
            count = f"{c['count']} calls" if title == "services" else f"{c['count']} samples"
            print(f"    {c['topic']}  {c['md_name']} ({c['layout_hash']})  "
                  f"{c['message_encoding']}  {count}  {rate}  {c['bytes']} bytes  "
                  f"{_time(c['first_ns'])} .. {_time(c['last_ns'])}  gaps {c['gaps']}"
                  + (f"  seq resets {c['seq_resets']}" if c["seq_resets"] else ""))


def run(args: argparse.Namespace) -> int:
    results = [file_info(p, args.quiet) for p in args.inputs]
    if args.json:
        json.dump({"files": results}, sys.stdout, indent=1)
        print()
    else:
        for d in results:
            _print(d)
    bad = [d for d in results if d["error"] is not None]
    if bad:
        raise BagError("; ".join(f"{d['path']}: at byte {d['error']['offset']}: "
                                 f"{d['error']['what']}" for d in bad))
    return 0
