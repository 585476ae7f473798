"""`ln_relay`: relays UDP and TCP links with injected faults until SIGTERM/SIGINT, then
prints its stats and writes them as JSON (docs/relay.md).  One line on stdout once every
link listens; --ready-file has the bound ports for a launcher that asked for port 0."""

from __future__ import annotations

import argparse
import asyncio
import json
import math
import os
import signal
import sys
from pathlib import Path
from typing import Any

from .addresses import RelayError, format_address, parse_address
from .core import Link, Relay
from .faults import FaultSpec

PROG = "ln_relay"


def probability(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"{text!r} is not a probability in 0..1")
    return value


def milliseconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of milliseconds >= 0")
    return value


def positive_milliseconds(text: str) -> float:
    value = milliseconds(text)
    if value == 0:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of milliseconds > 0")
    return value


def natural(text: str) -> int:
    if not (text.isascii() and text.isdigit()):
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer >= 0")
    return int(text)


def positive(text: str) -> int:
    value = natural(text)
    if value == 0:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer > 0")
    return value


def seconds(text: str) -> float:
    value = milliseconds(text)
    if value == 0:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds > 0")
    return value


class _LinkAction(argparse.Action):
    """--udp/--tcp LISTEN TARGET, kept in one list in command-line order (the order
    decides each link's random stream)."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: Any, option_string: str | None = None) -> None:
        listen, target = values
        try:
            link = Link(self.const, parse_address(listen, allow_port_zero=True),
                        parse_address(target))
        except ValueError as exc:
            raise argparse.ArgumentError(self, str(exc)) from None
        namespace.links = [*(namespace.links or []), link]


def build_parser() -> argparse.ArgumentParser:
    defaults = FaultSpec()
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Relay UDP datagrams and TCP connections from LISTEN to TARGET and "
                    "back, losing, delaying, duplicating and reordering them on the way, "
                    "as a lossy network would (docs/relay.md).  Addresses are HOST:PORT "
                    "or [V6HOST]:PORT; LISTEN port 0 picks a free port.  Faults apply to "
                    "both directions of every link unless --one-way.")
    parser.set_defaults(links=[])
    links = parser.add_argument_group("links (repeatable, at least one)")
    links.add_argument("--udp", nargs=2, metavar=("LISTEN", "TARGET"), action=_LinkAction,
                       const="udp", dest="links",
                       help="relay datagrams; each client gets its own socket to TARGET")
    links.add_argument("--tcp", nargs=2, metavar=("LISTEN", "TARGET"), action=_LinkAction,
                       const="tcp", dest="links",
                       help="relay connections; each gets its own connection to TARGET")
    faults = parser.add_argument_group("faults")
    faults.add_argument("--loss", type=probability, default=0.0, metavar="P",
                        help="probability a datagram is lost (TCP: a chunk waits a "
                             "retransmission timeout, everything behind it too)")
    faults.add_argument("--delay-ms", type=milliseconds, default=0.0, metavar="D",
                        help="one-way delay of every datagram or chunk")
    faults.add_argument("--jitter-ms", type=milliseconds, default=0.0, metavar="J",
                        help="the delay varies uniformly by ±J (never below 0); reorders "
                             "UDP, not TCP")
    faults.add_argument("--duplicate", type=probability, default=0.0, metavar="P",
                        help="probability a datagram is sent twice (UDP only)")
    faults.add_argument("--reorder", type=probability, default=0.0, metavar="P",
                        help="probability a datagram is held back behind the next one "
                             "(UDP only)")
    faults.add_argument("--reorder-flush-ms", type=milliseconds,
                        default=defaults.reorder_flush_ms, metavar="F",
                        help="a held datagram goes on its own after F ms without a next "
                             f"one (default {defaults.reorder_flush_ms:g})")
    faults.add_argument("--rto-ms", type=positive_milliseconds, default=defaults.rto_ms,
                        metavar="R",
                        help="TCP: retransmission timeout a lost chunk waits, doubling "
                             f"while it is lost again (default {defaults.rto_ms:g})")
    faults.add_argument("--rto-max-ms", type=positive_milliseconds,
                        default=defaults.rto_max_ms, metavar="R",
                        help=f"TCP: the doubling stops here (default {defaults.rto_max_ms:g})")
    faults.add_argument("--tcp-retries", type=natural, default=defaults.tcp_retries,
                        metavar="N",
                        help="TCP: a chunk lost N+1 times in a row resets the connection "
                             f"(default {defaults.tcp_retries})")
    faults.add_argument("--tcp-chunk", type=positive, default=defaults.tcp_chunk,
                        metavar="BYTES",
                        help="TCP: most bytes read, and faulted, at a time "
                             f"(default {defaults.tcp_chunk})")
    faults.add_argument("--queue-limit", type=positive, default=defaults.queue_limit,
                        metavar="BYTES",
                        help="most bytes waiting per direction (per TCP connection); UDP "
                             "drops beyond it, TCP stops reading "
                             f"(default {defaults.queue_limit})")
    faults.add_argument("--one-way", action="store_true",
                        help="faults only from the client to the target; replies pass "
                             "unharmed")
    faults.add_argument("--seed", type=natural, default=None, metavar="N",
                        help="seed of the random decisions (default: a random one, "
                             "printed); the same seed and input give the same decisions")
    run = parser.add_argument_group("running")
    run.add_argument("--udp-idle-s", type=seconds, default=120.0, metavar="S",
                     help="a UDP client's socket to the target closes after S seconds "
                          "without traffic (default 120)")
    run.add_argument("--ready-file", type=Path, metavar="PATH",
                     help="once listening, write the bound addresses here as JSON")
    run.add_argument("--stats-file", type=Path, metavar="PATH",
                     help="on SIGTERM/SIGINT, write the stats here as JSON")
    return parser


def fault_spec(args: argparse.Namespace) -> FaultSpec:
    return FaultSpec(loss=args.loss, delay_ms=args.delay_ms, jitter_ms=args.jitter_ms,
                     duplicate=args.duplicate, reorder=args.reorder,
                     reorder_flush_ms=args.reorder_flush_ms, rto_ms=args.rto_ms,
                     rto_max_ms=args.rto_max_ms, tcp_retries=args.tcp_retries,
                     tcp_chunk=args.tcp_chunk, queue_limit=args.queue_limit,
                     one_way=args.one_way)


def write_json(path: Path, value: Any) -> None:
    """Write atomically, so that a reader polling for the file never sees half of it."""
    temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        temporary.write_text(json.dumps(value, indent=2) + "\n")
        os.replace(temporary, path)
    except OSError as exc:
        temporary.unlink(missing_ok=True)
        raise RelayError(f"cannot write {path}: {exc.strerror or exc}") from None


def ready_info(relay: Relay) -> dict[str, Any]:
    return {"pid": os.getpid(), "seed": relay.seed,
            "links": [{"proto": link.proto, "listen": format_address(bound),
                       "host": bound[0], "port": bound[1],
                       "target": format_address(link.target)}
                      for link, bound in zip(relay.links, relay.bound, strict=True)]}


def plural(count: int, noun: str) -> str:
    return f"{count} {noun}" if count == 1 else f"{count} {noun}s"


def summary(relay: Relay) -> list[str]:
    """What is printed at the end: per link its peers, then a line per direction."""
    lines = []
    for stats in relay.stats:
        peers = (plural(stats.peers, "client") if stats.proto == "udp" else
                 f"{plural(stats.peers, 'connection')}, {stats.connect_failed} failed to "
                 f"connect, {stats.aborted} given up, {stats.resets} reset")
        lines.append(f"{PROG}: {stats.proto} {stats.listen} -> {stats.target}: {peers}")
        lines.append(f"{PROG}:   upstream: {stats.upstream.summary()}")
        lines.append(f"{PROG}:   downstream: {stats.downstream.summary()}")
    return lines


async def run(args: argparse.Namespace, faults: FaultSpec) -> int:
    relay = Relay(args.links, faults, args.seed, udp_idle_s=args.udp_idle_s)
    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    for signum in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(signum, stop.set)
    await relay.start()
    try:
        if args.ready_file:
            write_json(args.ready_file, ready_info(relay))
        listening = ", ".join(f"{link.proto} {format_address(bound)} -> "
                              f"{format_address(link.target)}"
                              for link, bound in zip(relay.links, relay.bound, strict=True))
        print(f"{PROG}: listening on {listening} (seed {relay.seed}, pid {os.getpid()})",
              flush=True)
        await stop.wait()
        report = relay.report()  # before close: `queued` is what the exit drops
        lines = summary(relay)
    finally:
        await relay.close()
    print("\n".join(lines), flush=True)
    if args.stats_file:
        write_json(args.stats_file, report)
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not args.links:
        parser.error("nothing to relay: give at least one --udp LISTEN TARGET or "
                     "--tcp LISTEN TARGET")
    if args.rto_max_ms < args.rto_ms:
        parser.error(f"--rto-max-ms ({args.rto_max_ms:g}) must be at least --rto-ms "
                     f"({args.rto_ms:g})")
    try:
        faults = fault_spec(args)
    except ValueError as exc:  # what the argument types did not already catch
        parser.error(str(exc))
    tcp = any(link.proto == "tcp" for link in args.links)
    if tcp and (faults.duplicate or faults.reorder):
        print(f"{PROG}: note: --duplicate and --reorder do not apply to TCP links",
              file=sys.stderr)
    try:
        return asyncio.run(run(args, faults))
    except RelayError as exc:
        print(f"{PROG}: error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
