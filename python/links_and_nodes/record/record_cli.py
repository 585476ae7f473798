"""`ln_record`: record topics into rotating MCAP files (docs/recording.md).

    ln_record -o DIR [TOPIC ...] [--all] [--regex RE] [--split-size 1GiB] [--duration S]
              [--compression zstd|lz4|none] [--encoding ros2|json|ln] [--manager HOST:PORT]

Topics named, matching a --regex or (--all) every topic are recorded as soon as the manager
knows them; its topic list is polled for topics that appear later.  SIGINT and SIGTERM end the
recording cleanly; a SIGKILL leaves files readable up to their last complete chunk.
Exit status: 0 done, 1 an error (manager unreachable, a file that cannot be written), 2 usage.
"""

from __future__ import annotations

import argparse
import os
import re
import signal
import sys
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..mcap_chunk import COMPRESSIONS, DEFAULT_CHUNK_SIZE
from ..tool_output import say_line
from .defaults import DEFAULT_BUFFER_MEMORY, DEFAULT_ENCODING, ENCODINGS, MAX_BUFFERS

if TYPE_CHECKING:
    from .service_recording import ServiceRecording

_UNITS = {"": 1, "B": 1, "K": 1000, "KB": 1000, "KIB": 1 << 10, "M": 1000**2, "MB": 1000**2,
          "MIB": 1 << 20, "G": 1000**3, "GB": 1000**3, "GIB": 1 << 30, "T": 1000**4,
          "TB": 1000**4, "TIB": 1 << 40}
TICK = 0.1  # seconds between looks at the stop flag, the clock and the progress line


def parse_size(text: str) -> int:
    """Bytes of "1GiB", "500M", "4096", ...: KiB/MiB/GiB are powers of 2, K/M/G of 10."""
    match = re.fullmatch(r"\s*(\d+(?:\.\d+)?)\s*([A-Za-z]*)\s*", text)
    if not match or match.group(2).upper() not in _UNITS:
        raise argparse.ArgumentTypeError(f"not a size: {text!r} (e.g. 1GiB, 500MB, 4096)")
    return int(float(match.group(1)) * _UNITS[match.group(2).upper()])


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"not a positive number of seconds: {text!r}")
    return value


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(
        prog="ln_record", description="Record links_and_nodes topics into MCAP files.")
    ap.add_argument("topics", nargs="*", metavar="TOPIC", help="topic to record")
    ap.add_argument("-o", "--output", required=True, type=Path, metavar="DIR",
                    help="directory for the files PREFIX_NNNN.mcap (created if missing)")
    ap.add_argument("-a", "--all", action="store_true",
                    help="every topic the manager knows, also those that appear later")
    ap.add_argument("-e", "--regex", action="append", default=[], metavar="RE",
                    help="topics whose whole name matches RE (may be repeated)")
    ap.add_argument("--split-size", type=parse_size, default=1 << 30, metavar="SIZE",
                    help="start a new file once one reaches SIZE (default 1GiB; 0: never)")
    ap.add_argument("--duration", type=_seconds, metavar="S", help="stop after S seconds")
    ap.add_argument("--compression", choices=COMPRESSIONS, default="zstd",
                    help="of each chunk (default zstd)")
    ap.add_argument("--encoding", choices=ENCODINGS, default=DEFAULT_ENCODING,
                    help="how samples are stored: ros2 (CDR, decoded by Foxglove and "
                    "Lichtblick), json, or ln (the raw bytes, for any md) (default "
                    f"{DEFAULT_ENCODING}; docs/recording.md, Encodings)")
    ap.add_argument("--chunk-size", type=parse_size, default=DEFAULT_CHUNK_SIZE,
                    metavar="SIZE", help="samples per chunk, in bytes (default 1MiB)")
    ap.add_argument("--flush-interval", type=_seconds, default=1.0, metavar="S",
                    help="write the open chunk at least every S seconds (default 1), so a "
                    "killed recorder loses at most that much")
    ap.add_argument("--buffers", type=int, metavar="N",
                    help=f"queued buffers per topic (1..{MAX_BUFFERS}; default: as many as "
                    "--buffer-memory holds)")
    ap.add_argument("--buffer-memory", type=parse_size, default=DEFAULT_BUFFER_MEMORY,
                    metavar="SIZE", help="queued samples per topic, in bytes (default 64MiB)")
    ap.add_argument("--prefix", help="file name prefix (default ln_record_YYYYmmdd_HHMMSS)")
    ap.add_argument("--manager", metavar="HOST:PORT",
                    help="the manager (default $LN_MANAGER)")
    ap.add_argument("--md-dir", action="append", default=[], metavar="DIR",
                    help="search DIR for message definitions first (may be repeated)")
    ap.add_argument("--services", action="append", default=[], metavar="RE",
                    help="also record the calls of the services whose whole name matches RE "
                    "(may be repeated; docs/recording.md, Service calls)")
    ap.add_argument("--logs", action="store_true",
                    help="also record the manager's log lines (ln_log, ln.LogHandler, "
                         "log_level_regex) as foxglove.Log on channel ln.log")
    ap.add_argument("--poll", type=_seconds, default=1.0, metavar="S",
                    help="look for new topics every S seconds (default 1)")
    ap.add_argument("-q", "--quiet", action="store_true",
                    help="print errors only (no per-topic lines, no summary)")
    return ap


def _say(args: argparse.Namespace, text: str) -> None:
    if not args.quiet:
        say_line("ln_record", text)


def _mb(n: float) -> str:
    return f"{n / 1e6:.1f} MB"


class Selection:
    """Which topics of the manager's list to record; each decided once."""

    def __init__(self, args: argparse.Namespace) -> None:
        self.names = set(args.topics)
        self.regexes = [re.compile(r) for r in args.regex]
        self.all = args.all
        self.seen: set[str] = set()

    def wanted(self, topic: str) -> bool:
        return (self.all or topic in self.names
                or any(r.fullmatch(topic) for r in self.regexes))

    def new(self, listing: list[dict[str, Any]]) -> list[tuple[str, str]]:
        """(topic, md name) of the wanted topics in `listing` not decided before."""
        out = []
        for entry in listing:
            name = str(entry.get("name", ""))
            if name and name not in self.seen and self.wanted(name):
                self.seen.add(name)
                out.append((name, str(entry.get("md_name", ""))))
        return out


class Session:
    """One run: manager connection, recorder, output, progress."""

    def __init__(self, args: argparse.Namespace, address: str) -> None:
        import links_and_nodes as ln
        from links_and_nodes.tools.scripting import connect

        from .recorder import Recorder  # the writer: numpy, ln_generate, libln
        from .service_recording import ServiceRecording
        from .split_writer import SplitWriter

        self.args = args
        self.address = address
        self.selection = Selection(args)
        self.listing: Any = None
        self._connect = connect
        self._listing_error: str | None = None
        self.client = ln.client("ln_record", address)
        prefix = args.prefix or time.strftime("ln_record_%Y%m%d_%H%M%S")
        self.out = SplitWriter(args.output, prefix, args.compression, args.chunk_size,
                               args.split_size)
        self.recorder = Recorder(self.client, self.out, args.buffers, args.buffer_memory,
                                 args.encoding)
        self.tty = sys.stderr.isatty()
        self.services = (ServiceRecording(self.recorder, address, args.services, self._line)
                         if args.services else None)
        self.logs = None
        if args.logs:
            from .log_recording import LogRecording

            self.logs = LogRecording(self.recorder, address, connect, self._line)
        self._last = (time.monotonic(), 0, 0)
        self._rates = (0.0, 0.0)

    def poll_topics(self) -> None:
        try:
            if self.listing is None:
                self.listing = self._connect(self.address)
            topics = self.listing.topics()
        except Exception as exc:  # noqa: BLE001 - ManagerError, lost connection: retry later
            if self.listing is not None:
                self.listing.close()
                self.listing = None
            if str(exc) != self._listing_error:
                self._listing_error = str(exc)
                self._line(f"cannot list the manager's topics (will retry): {exc}")
            return
        self._listing_error = None
        for topic, md_name in self.selection.new(topics):
            why = self.recorder.add(topic, md_name)
            if why is None:
                rec = self.recorder.topics[topic]
                self._line(f"recording '{topic}' ({md_name}, {rec.buffers} buffers)")
            else:
                self._line(f"not recording '{topic}': {why}")

    def _line(self, text: str) -> None:
        if self.tty and not self.args.quiet:
            sys.stderr.write("\r\033[K")
        _say(self.args, text)

    def progress(self) -> None:
        if not self.tty or self.args.quiet:
            return
        now = time.monotonic()
        t, samples, nbytes = self._last
        rec = self.recorder
        if now - t >= 0.5:
            self._rates = ((rec.samples - samples) / (now - t), (rec.bytes - nbytes) / (now - t))
            self._last = (now, rec.samples, rec.bytes)
        rate, byte_rate = self._rates
        sys.stderr.write(
            f"\r\033[K{rec.samples} samples, {_mb(rec.bytes)} ({rate:.0f}/s, "
            f"{_mb(byte_rate)}/s), {rec.drops} dropped, {len(rec.topics)} topics, "
            f"file {self.out.files[-1].name}")
        sys.stderr.flush()

    def finish(self) -> int:
        if self.services is not None:
            self.services.stop()
        if self.logs is not None:
            self.logs.stop()
        self.recorder.stop()
        error = self.recorder.error
        try:
            self.out.close()
        except OSError as exc:
            error = error or f"cannot write {self.out.writer.path}: {exc}"
        self.client.close()
        if self.listing is not None:
            self.listing.close()
        if self.tty and not self.args.quiet:
            sys.stderr.write("\r\033[K")
        rec = self.recorder
        files = ", ".join(str(p) for p in self.out.files)
        _say(self.args, f"{rec.samples} samples ({_mb(rec.bytes)}) of {len(rec.topics)} topics, "
             f"{rec.drops} dropped, {_calls(self.services)}"
             f"{'' if self.logs is None else f'{self.logs.lines} log lines, '}"
             f"in {len(self.out.files)} files: "
             f"{files}")
        if error:
            print(f"ln_record: error: {error}", file=sys.stderr)
            return 1
        return 0


def _calls(services: ServiceRecording | None) -> str:
    """The summary's part about service calls ("" without --services)."""
    if services is None:
        return ""
    return (f"{services.calls} calls of {len(services.counts)} services "
            f"({services.drops} dropped), ")


def run(args: argparse.Namespace) -> int:
    import links_and_nodes as ln

    address = args.manager or os.environ.get("LN_MANAGER")
    if not address:
        print("ln_record: error: no manager: give --manager HOST:PORT or set LN_MANAGER",
              file=sys.stderr)
        return 2
    for d in args.md_dir:
        ln.add_message_definition_dir(d)
    stop = threading.Event()

    def on_signal(signum: int, frame: Any) -> None:
        stop.set()

    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    try:
        args.output.mkdir(parents=True, exist_ok=True)
        session = Session(args, address)
    except (OSError, ImportError, ValueError, ln.LnError) as exc:
        print(f"ln_record: error: {exc}", file=sys.stderr)
        return 1
    started = time.monotonic()
    next_poll = next_flush = started
    try:
        while not stop.is_set() and not session.recorder.stopping:
            now = time.monotonic()
            if args.duration is not None and now - started >= args.duration:
                break
            if now >= next_poll:
                session.poll_topics()
                next_poll = now + args.poll
            if now >= next_flush:
                if next_flush > started:
                    session.recorder.flush()
                next_flush = now + args.flush_interval
            session.progress()
            stop.wait(TICK)
    finally:
        code = session.finish()
    return code


def main(argv: list[str] | None = None) -> int:
    ap = parser()
    args = ap.parse_args(argv)
    if not (args.topics or args.all or args.regex or args.services or args.logs):
        ap.error("name topics to record, or give --all, --regex, --services or --logs")
    for r in args.services:
        try:
            re.compile(r)
        except re.error as exc:
            ap.error(f"--services {r!r}: {exc}")
    if args.buffers is not None and not 1 <= args.buffers <= MAX_BUFFERS:
        ap.error(f"--buffers must be 1..{MAX_BUFFERS}")
    for r in args.regex:
        try:
            re.compile(r)
        except re.error as exc:
            ap.error(f"--regex {r!r}: {exc}")
    if args.prefix is not None and (not args.prefix or "/" in args.prefix):
        ap.error("--prefix must be a file name without '/'")
    return run(args)


if __name__ == "__main__":
    sys.exit(main())
