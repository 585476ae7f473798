"""`ln_foxglove`: serve a links_and_nodes system to Foxglove, Lichtblick and other clients of
the Foxglove WebSocket protocol (docs/webui.md, "Foxglove and Lichtblick").

    ln_foxglove [--manager HOST:PORT] [--host ADDR] [--port PORT] [--direct] [--origin P]...
                [--topic SPEC]... [--service SPEC]... [--exclude PATTERN]... [--no-services]
                [--md-dir DIR]... [--name NAME] [--poll S] [-v]

SPEC: `PATTERN[,queued[=N]][,latest][,rate=HZ]` for topics, `PATTERN[,timeout=S]` for
services.  SIGINT/SIGTERM end it, SIGUSR1 prints the statistics.  Exit status: 0 stopped,
1 an error (foxglove-sdk not installed, the manager unreachable, the port taken), 2 usage.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
import time
from typing import TYPE_CHECKING

from ..tool_output import say_line
from .config import DEFAULT_HOST, DEFAULT_PORT, ConfigError, FoxgloveConfig

if TYPE_CHECKING:
    from .bridge import Bridge

INSTALL_HINT = "pip install foxglove-sdk  (or: pip install 'links_and_nodes[foxglove]')"
TICK = 0.1


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(
        prog="ln_foxglove", description="Serve links_and_nodes topics and services over the "
        "Foxglove WebSocket protocol (Foxglove, Lichtblick, PlotJuggler).")
    ap.add_argument("--manager", metavar="HOST:PORT", help="the manager (default $LN_MANAGER)")
    ap.add_argument("--host", default=DEFAULT_HOST,
                    help=f"address to listen on (default {DEFAULT_HOST}: this host only)")
    ap.add_argument("--port", type=int, default=DEFAULT_PORT,
                    help=f"port to listen on (default {DEFAULT_PORT}; 0: any free one)")
    ap.add_argument("--direct", action="store_true",
                    help="let the foxglove-sdk server listen on the port itself: only clients "
                    "asking for foxglove.sdk.v1 connect, one copy less")
    ap.add_argument("--origin", action="append", default=[], metavar="PATTERN",
                    help="refuse browsers whose Origin matches no PATTERN, e.g. "
                    "'https://app.foxglove.dev' (repeatable; default: no check)")
    ap.add_argument("--topic", action="append", default=[], metavar="SPEC",
                    help="topics to offer and how, PATTERN[,queued[=N]][,latest][,rate=HZ] "
                    "(repeatable; default: every topic, latest mode, no rate limit)")
    ap.add_argument("--service", action="append", default=[], metavar="SPEC",
                    help="services to offer, PATTERN[,timeout=S] (repeatable; default: "
                    "every service, timeout 10 s)")
    ap.add_argument("--exclude", action="append", default=[], metavar="PATTERN",
                    help="topics and services not to offer (repeatable)")
    ap.add_argument("--no-services", action="store_true", help="offer no services")
    ap.add_argument("--md-dir", action="append", default=[], metavar="DIR",
                    help="also search DIR for message definitions, after the manager's "
                    "search path (repeatable)")
    ap.add_argument("--name", default="ln_foxglove", help="client name at the manager")
    ap.add_argument("--poll", type=float, default=1.0, metavar="S",
                    help="look for new and gone topics and services every S seconds "
                    "(default 1)")
    ap.add_argument("-v", "--verbose", action="store_true",
                    help="say when clients subscribe and unsubscribe and calls fail")
    return ap


def build_config(args: argparse.Namespace) -> FoxgloveConfig:
    config = FoxgloveConfig(manager=args.manager, host=args.host, port=args.port,
                            direct=args.direct, origins=list(args.origin),
                            exclude=list(args.exclude),
                            offer_services=not args.no_services, name=args.name,
                            md_dirs=list(args.md_dir), poll=args.poll, verbose=args.verbose)
    for spec in args.topic:
        config.add_topic_spec(spec)
    for spec in args.service:
        config.add_service_spec(spec)
    config.check()
    return config


def say(text: str) -> None:
    say_line("ln_foxglove", text)


def run(config: FoxgloveConfig) -> int:
    from ..tools.introspection.commands import CommandError
    from ..tools.scripting import ManagerError
    from .bridge import Bridge

    address = config.manager or os.environ.get("LN_MANAGER")
    if not address:
        say("error: no manager: give --manager HOST:PORT or set LN_MANAGER")
        return 2
    if config.md_dirs:
        os.environ["LN_MESSAGE_DEFINITION_DIRS"] = os.pathsep.join(
            config.md_dirs + [d for d in os.environ.get("LN_MESSAGE_DEFINITION_DIRS", "")
                              .split(os.pathsep) if d])
    stop = threading.Event()
    stats_wanted = threading.Event()
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGUSR1, lambda *_: stats_wanted.set())
    bridge = Bridge(config, address, say)
    try:
        bridge.start()
        next_poll = time.monotonic()
        while not stop.is_set():
            now = time.monotonic()
            if now >= next_poll:
                bridge.poll()
                next_poll = now + config.poll
            if stats_wanted.is_set():
                stats_wanted.clear()
                report(bridge, "SIGUSR1")
            stop.wait(TICK)
    except (ManagerError, CommandError, OSError, RuntimeError) as exc:
        say(f"error: {exc}")
        return 1
    finally:
        report(bridge, "exit")
        bridge.close()
    say("stopped")
    return 0


def report(bridge: Bridge, why: str) -> None:
    lines = bridge.stats_lines()
    say(f"statistics ({why}):" + ("" if lines else " nothing bridged"))
    for line in lines:
        say(f"  {line}")


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    try:
        config = build_config(args)
    except ConfigError as exc:
        print(f"ln_foxglove: error: {exc}", file=sys.stderr)
        return 2
    try:
        import foxglove  # noqa: F401
    except ImportError:
        print(f"ln_foxglove: error: the Python package foxglove-sdk is not installed: "
              f"{INSTALL_HINT}", file=sys.stderr)
        return 1
    return run(config)


if __name__ == "__main__":
    sys.exit(main())
