"""`ln_play`: publish the samples of MCAP recordings again (docs/recording.md).

    ln_play FILE.mcap... [--rate X] [--loop] [--topics T ...] [--start S] [--remap A=B]

The files (the pieces of one split recording, in order) are read whole first; a corrupt or
cut-short file, or a topic whose md here has another layout than the recorded one, is refused
with nothing published.  Exit status: 0 done (or Ctrl-C), 1 refused or failed, 2 usage.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import tempfile
from typing import Any

from ..mcap_format import McapError, McapTruncatedError
from .player import PlayError, check_files, open_publishers, play, resolve_classes


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not 0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"not a positive number: {text!r}")
    return value


def _not_negative(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not 0 <= value < float("inf"):
        raise argparse.ArgumentTypeError(f"not a number of seconds >= 0: {text!r}")
    return value


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(
        prog="ln_play", description="Publish the samples of MCAP recordings of ln_record.")
    ap.add_argument("files", nargs="+", metavar="FILE", help="MCAP file (several: in order)")
    ap.add_argument("--rate", type=_positive, default=1.0, metavar="X",
                    help="play X times as fast as recorded (default 1)")
    ap.add_argument("--loop", action="store_true", help="start again at the end, until Ctrl-C")
    ap.add_argument("--topics", nargs="+", metavar="T", help="play only these topics")
    ap.add_argument("--start", type=_not_negative, default=0.0, metavar="S",
                    help="begin S seconds after the recording's first sample")
    ap.add_argument("--remap", action="append", default=[], metavar="FROM=TO",
                    help="publish recorded topic FROM as topic TO (may be repeated)")
    ap.add_argument("--wait-for-subscribers", action="store_true",
                    help="a write waits while a queued subscriber has no free buffer: slow "
                    "subscribers lose nothing, the timing stretches instead")
    ap.add_argument("--partial", action="store_true",
                    help="play a file that ends inside a record up to that record")
    ap.add_argument("--manager", metavar="HOST:PORT", help="the manager (default $LN_MANAGER)")
    ap.add_argument("--md-dir", action="append", default=[], metavar="DIR",
                    help="search DIR for message definitions first (may be repeated)")
    ap.add_argument("-q", "--quiet", action="store_true", help="print errors only")
    return ap


def _say(args: argparse.Namespace, text: str) -> None:
    if not args.quiet:
        print(f"ln_play: {text}", file=sys.stderr, flush=True)


def run(args: argparse.Namespace, remap: dict[str, str]) -> int:
    import links_and_nodes as ln

    for d in args.md_dir:
        ln.add_message_definition_dir(d)
    address = args.manager or os.environ.get("LN_MANAGER")
    if not address:
        raise PlayError("no manager: give --manager HOST:PORT or set LN_MANAGER")
    try:
        rec = check_files(args.files, allow_truncated=args.partial)
    except McapTruncatedError as exc:
        raise PlayError(f"{exc} (--partial plays the samples before it)") from None
    except McapError as exc:
        raise PlayError(str(exc)) from None
    for note in rec.notes:
        _say(args, note)
    topics = rec.topics
    if args.topics:
        unknown = [t for t in args.topics if t not in topics]
        if unknown:
            raise PlayError(f"not in the recording: {', '.join(unknown)} (it has: "
                            f"{', '.join(sorted(topics)) or 'no topics'})")
        topics = {t: topics[t] for t in args.topics}
    unknown = [t for t in remap if t not in topics]
    if unknown:
        raise PlayError(f"--remap of topics that are not played: {', '.join(unknown)}")
    try:
        client = ln.client("ln_play", address)
    except ln.LnError as exc:
        raise PlayError(str(exc)) from None
    with client, tempfile.TemporaryDirectory(prefix="ln_play.") as schema_dir:
        for note in resolve_classes(topics, schema_dir):
            _say(args, note)
        ports = open_publishers(client, topics, remap, args.wait_for_subscribers)
        total = sum(rec.counts.get(t, 0) for t in topics)
        span = ((rec.last_ns or 0) - (rec.first_ns or 0)) / 1e9
        _say(args, f"playing {total} samples of {len(topics)} topics ({span:.3f} s recorded) "
             f"at rate {args.rate:g}{', looping' if args.loop else ''}")
        published = 0

        def count(n: int) -> None:
            nonlocal published
            published = n

        try:
            play(rec, ports, args.rate, args.start, args.loop, count)
        except KeyboardInterrupt:
            _say(args, f"interrupted after {published} samples")
            return 0
        _say(args, f"published {published} samples")
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = parser()
    args = ap.parse_args(argv)
    remap: dict[str, str] = {}
    for item in args.remap:
        old, eq, new = item.partition("=")
        if not eq or not old or not new:
            ap.error(f"--remap takes FROM=TO, not {item!r}")
        remap[old] = new
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        return run(args, remap)
    except PlayError as exc:
        print(f"ln_play: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("ln_play: interrupted", file=sys.stderr)
        return 130


def _interrupt(signum: int, frame: Any) -> None:
    raise KeyboardInterrupt


if __name__ == "__main__":
    sys.exit(main())
