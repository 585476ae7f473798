"""`ln_play`: publish the samples of MCAP recordings again (docs/recording.md).

    ln_play FILE.mcap... [--rate X] [--loop] [--topics T ...] [--start S] [--remap A=B]
            [--start-paused] [--hold] [--control-service NAME] [--clock [HZ]]

The files (the pieces of one split recording, in order) are read whole first; a corrupt or
cut-short file, or a topic whose md here has another layout than the recorded one, is refused
with nothing published.  While it plays, the keyboard (stdin a terminal) and the service
`<client>.control` (md ln/player) pause, step, seek and change the rate; `--clock` publishes
the replay clock (docs/recording.md, "Replay control and the replay clock").
Exit status: 0 done (or Ctrl-C, q), 1 refused or failed, 2 usage.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
import tempfile
from collections.abc import Iterator
from typing import Any

from ..mcap_format import McapError, McapTruncatedError
from ..tool_output import say_line
from . import control_service, keyboard, service_replay
from .control import Controller
from .playback import Playback, Quit
from .player import PlayError, check_files, open_publishers, resolve_classes
from .replay_clock import CLOCK_TOPIC, ReplayClock


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
    ap.add_argument("--start-paused", action="store_true",
                    help="start paused (resume, step or seek through the keyboard or service)")
    ap.add_argument("--hold", action="store_true",
                    help="at the end stay (finished, seekable) until q, Ctrl-C or SIGTERM")
    ap.add_argument("--no-keyboard", action="store_true",
                    help="leave the terminal alone (keys control ln_play when stdin is one)")
    ap.add_argument("--control-service", metavar="NAME",
                    help="name of the control service (md ln/player; default: the client "
                    "name + '.control', e.g. ln_play.control)")
    ap.add_argument("--clock", nargs="?", type=_positive, const=100.0, metavar="HZ",
                    help=f"publish the replay clock on topic {CLOCK_TOPIC} (md ln/clock) HZ "
                    "times a second (default 100) and on every pause, seek and rate change")
    ap.add_argument("--clock-topic", default=CLOCK_TOPIC, metavar="TOPIC",
                    help=f"the replay clock's topic (default {CLOCK_TOPIC})")
    ap.add_argument("--services", action="store_true",
                    help="also issue the recorded service calls again to the live services "
                    "at their recorded times (docs/recording.md, Service calls)")
    ap.add_argument("--manager", metavar="HOST:PORT", help="the manager (default $LN_MANAGER)")
    ap.add_argument("--md-dir", action="append", default=[], metavar="DIR",
                    help="search DIR for message definitions first (may be repeated)")
    ap.add_argument("-q", "--quiet", action="store_true", help="print errors only")
    return ap


def _say(args: argparse.Namespace, text: str) -> None:
    if not args.quiet:
        say_line("ln_play", text)


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
        return _play(args, client, rec, ports)
    return 0


def _play(args: argparse.Namespace, client: Any, rec: Any, ports: Any) -> int:
    """The replay with its controls: the service, the keyboard on a terminal, the clock."""
    start = (rec.first_ns or 0) + int(args.start * 1e9)
    pb = Playback(rec, ports, args.rate, start, args.loop, args.start_paused, args.hold)
    calls = (service_replay.start(args.manager or os.environ["LN_MANAGER"], args, rec, pb,
                                  lambda text: _say(args, text)) if args.services else None)
    name = args.control_service or control_service.default_name(client.name)
    try:
        control_service.provide(client, name, pb)
        clock = ReplayClock(client, args.clock_topic, args.clock) if args.clock else None
    except Exception as exc:  # noqa: BLE001 - LnError & co. carry libln's text
        raise PlayError(f"cannot set up the controls: {exc}") from None
    _say(args, f"control service: {name}" + (f"; clock on {args.clock_topic}" if clock else ""))
    tty = not args.no_keyboard and keyboard.usable(sys.stdin.fileno())
    keys = keyboard.KeyReader(sys.stdin.fileno()) if tty else None
    ctl = Controller(pb, client, keys.commands if keys else None, clock,
                     keyboard.status_line if tty and not args.quiet else None)
    if clock is not None:
        clock.publish(pb)
    try:
        with keyboard.cbreak(sys.stdin.fileno()) if keys else _nothing():
            if keys is not None:
                _say(args, keyboard.HELP)
                keys.start()
            try:
                published = pb.run(ctl.wait)
                if calls is not None:
                    calls.wait()
            finally:
                if calls is not None:
                    calls.stop()
                    _say(args, f"issued {calls.issued} service calls ({calls.failed} failed)")
                if keys is not None:
                    keys.stop()
                    sys.stderr.write("\n")
    except (KeyboardInterrupt, Quit) as exc:
        _say(args, f"{'quit' if isinstance(exc, Quit) else 'interrupted'} after {pb.played} "
             "samples")
        return 0
    _say(args, f"published {published} samples")
    return 0


@contextlib.contextmanager
def _nothing() -> Iterator[None]:
    yield


def _clock_without_hz(argv: list[str]) -> list[str]:
    """`--clock` followed by a file (not a number of Hz) means the default rate: argparse
    would take the file for HZ."""
    out = list(argv)
    for i, arg in enumerate(out):
        if arg == "--clock":
            try:
                float(out[i + 1])
            except (IndexError, ValueError):
                out[i] = "--clock=100"
    return out


def main(argv: list[str] | None = None) -> int:
    ap = parser()
    args = ap.parse_args(_clock_without_hz(sys.argv[1:] if argv is None else argv))
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
