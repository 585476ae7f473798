"""`ln_bag merge`: the pieces of a split recording and the recordings of several hosts into
one file, in publish-time order, each (topic, seq) once; streaming with a bounded
reordering window (ordering.py)."""

from __future__ import annotations

import argparse

from .copying import finish
from .ordering import WINDOW_NS, merged, unique
from .output import Output, check_output
from .progress import Progress
from .source import Source
from .timespec import parse_duration

HELP = "merge recordings by publish time, removing duplicate (topic, seq)"


def add_arguments(ap: argparse.ArgumentParser) -> None:
    ap.add_argument("--window", type=parse_duration, default=WINDOW_NS, metavar="S",
                    help="how far (seconds) samples in one file may be out of publish-time "
                    "order, and duplicates apart (default 1)")


def run(args: argparse.Namespace) -> int:
    check_output(args.output, args.inputs, args.force)
    sources = [Source(p) for p in args.inputs]
    out = Output(args.output, args)
    progress = Progress("ln_bag merge", enabled=None if not args.quiet else False)
    channels: dict[int, int] = {}  # by id of the input's TopicInfo
    try:
        for info, s in unique(merged(sources, args.window), args.window):
            channel = channels.get(id(info))
            if channel is None:
                channel = channels[id(info)] = out.channel(info)
            out.write(channel, s.seq, s.publish_time_ns, s.data)
            progress.add(len(s.data))
    finally:
        progress.done()
        out.close()
    return finish(args, out, sources)
