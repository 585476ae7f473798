"""`ln_bag cut`: the samples with start <= publish time <= end (both included), from one
recording (or the pieces of one, in order) into one file; chunks inside the range are
copied as stored, those outside passed over, only the two at its edges decoded."""

from __future__ import annotations

import argparse

from .copying import FIRST, LAST, Rules, copy
from .errors import UsageError
from .summary import first_time
from .timespec import parse_time

HELP = "keep the samples with START <= publish time <= END"


def add_arguments(ap: argparse.ArgumentParser) -> None:
    ap.add_argument("--start", type=parse_time, metavar="TIME",
                    help="ns since the epoch, ISO 8601 with zone, or +S / Ss: seconds after "
                    "the first sample (default: from the first sample)")
    ap.add_argument("--end", type=parse_time, metavar="TIME",
                    help="same syntax (default: to the last sample)")


def run(args: argparse.Namespace) -> int:
    if args.start is None and args.end is None:
        raise UsageError("give --start, --end or both")
    first = None
    if any(t is not None and t.relative for t in (args.start, args.end)):
        first = first_time(args.inputs)
    start = args.start.resolve(first) if args.start is not None else None
    end = args.end.resolve(first) if args.end is not None else None
    if start is not None and end is not None and end < start:
        raise UsageError(f"--end {args.end.text} is before --start {args.start.text}")
    return copy(args, Rules(start=start if start is not None else FIRST,
                            end=end if end is not None else LAST))
