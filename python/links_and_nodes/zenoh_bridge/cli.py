"""`ln_zenoh`: bridge links_and_nodes topics and services to Zenoh (docs/zenoh.md).

    ln_zenoh [-c FILE.toml|.json] [--manager HOST:PORT] [--prefix P] [--mode peer|client]
             [--listen EP]... [--connect EP]... [--zenoh-config FILE] [--remote PREFIX]
             [--out SPEC]... [--in SPEC]... [--service-out SPEC]... [--service-in SPEC]...
             [--ros2 [--ros2-domain N]] [--stats-file PATH] [--stats-interval S] [-v]
             [--native auto|on|off] [--batch on|off]

SPEC: `PATTERN[,queued[=N]][,latest][,rate=HZ][,remote=PREFIX]` for topics,
`PATTERN[,remote=PREFIX][,timeout=S]` for services.  SIGINT/SIGTERM end it, SIGUSR1 prints the
statistics (and writes --stats-file).  Exit status: 0 done, 1 an error (zenoh not installed,
manager unreachable, a session that cannot open), 2 usage or configuration.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
import time
from typing import Any

from ..tool_output import say_line
from .config import BridgeConfig, ConfigError, load_file, service_spec, topic_spec
from .session import INSTALL_HINT, ZenohMissing, import_zenoh

VERBOSE_STATS_INTERVAL = 10.0  # seconds between statistics at -v without --stats-interval
TICK = 0.1


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(
        prog="ln_zenoh", description="Bridge links_and_nodes topics and services to Zenoh.")
    ap.add_argument("-c", "--config", metavar="FILE", help="settings and rules (.toml or .json)")
    ap.add_argument("--manager", metavar="HOST:PORT", help="the manager (default $LN_MANAGER)")
    ap.add_argument("--prefix", help="key expression prefix of this bridge (default "
                    "ln/<instance>)")
    ap.add_argument("--mode", choices=("peer", "client"), help="Zenoh mode (default peer)")
    ap.add_argument("--listen", action="append", default=[], metavar="ENDPOINT",
                    help="Zenoh endpoint to listen on, e.g. tcp/0.0.0.0:7447 (repeatable)")
    ap.add_argument("--connect", action="append", default=[], metavar="ENDPOINT",
                    help="Zenoh endpoint to connect to, e.g. tcp/10.0.0.1:7447 (repeatable)")
    ap.add_argument("--zenoh-config", metavar="FILE",
                    help="a Zenoh config file (JSON5) to start from: TLS, access control, ...")
    ap.add_argument("--remote", metavar="PREFIX",
                    help="prefix of the other bridge, for --in and --service-in")
    ap.add_argument("--out", action="append", default=[], metavar="SPEC",
                    help="topics to send to Zenoh (repeatable)")
    ap.add_argument("--in", dest="in_", action="append", default=[], metavar="SPEC",
                    help="topics to take from Zenoh and publish here (repeatable)")
    ap.add_argument("--service-out", action="append", default=[], metavar="SPEC",
                    help="local services to serve to Zenoh (repeatable)")
    ap.add_argument("--service-in", action="append", default=[], metavar="SPEC",
                    help="services of the remote bridge to provide here (repeatable)")
    ap.add_argument("--ros2", action="store_true", default=None,
                    help="also publish outbound topics under rmw_zenoh-like keys, as CDR")
    ap.add_argument("--ros2-domain", type=int, metavar="N", help="ROS domain id (default 0)")
    ap.add_argument("--name", help="client name at the manager (default ln_zenoh)")
    ap.add_argument("--md-dir", action="append", default=[], metavar="DIR",
                    help="search DIR for message definitions first (repeatable)")
    ap.add_argument("--stats-file", metavar="PATH",
                    help="write the counters as JSON here on SIGUSR1, periodically and at exit")
    ap.add_argument("--stats-interval", type=float, metavar="S",
                    help=f"print statistics every S seconds (-v: {VERBOSE_STATS_INTERVAL:g})")
    ap.add_argument("--poll", type=float, metavar="S",
                    help="look for new topics and services every S seconds (default 1)")
    ap.add_argument("--native", choices=("auto", "on", "off"),
                    help="topic samples through the native core: auto (default: if it is "
                    "built), on (an error if not), off (through Python)")
    ap.add_argument("--batch", choices=("on", "off"),
                    help="several small samples per Zenoh message between two bridges with "
                    "the native core, where the other one takes them (default on)")
    ap.add_argument("-v", "--verbose", action="store_true",
                    help="print statistics periodically")
    return ap


def build_config(args: argparse.Namespace) -> BridgeConfig:
    config = load_file(args.config) if args.config else BridgeConfig()
    for key in ("prefix", "mode", "zenoh_config", "remote", "ros2", "ros2_domain", "name",
                "manager", "stats_file", "stats_interval", "poll", "native"):
        value = getattr(args, key)
        if value is not None:
            setattr(config, key, value)
    if args.batch is not None:
        config.batch = args.batch == "on"
    config.listen += args.listen
    config.connect += args.connect
    config.md_dirs += args.md_dir
    config.topics += [topic_spec(s, "out") for s in args.out]
    config.topics += [topic_spec(s, "in") for s in args.in_]
    config.services += [service_spec(s, "out") for s in args.service_out]
    config.services += [service_spec(s, "in") for s in args.service_in]
    if args.verbose and not config.stats_interval:
        config.stats_interval = VERBOSE_STATS_INTERVAL
    if not config.poll > 0:
        raise ConfigError("poll must be a positive number of seconds")
    config.check()
    return config


def say(text: str) -> None:
    say_line("ln_zenoh", text)


def report(bridge: Any, config: BridgeConfig, why: str) -> None:
    say(f"statistics ({why}):")
    for line in bridge.stats.lines():
        say_line("ln_zenoh", f"  {line}")
    if config.stats_file:
        try:
            bridge.stats.write(config.stats_file)
        except OSError as exc:
            say(f"cannot write {config.stats_file}: {exc}")


def run(config: BridgeConfig) -> int:
    import links_and_nodes as ln

    from .bridge import Bridge

    address = config.manager or os.environ.get("LN_MANAGER")
    if not address:
        say("error: no manager: give --manager HOST:PORT or set LN_MANAGER")
        return 2
    for d in config.md_dirs:
        ln.add_message_definition_dir(d)
    stop = threading.Event()
    stats_wanted = threading.Event()
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGUSR1, lambda *_: stats_wanted.set())
    bridge = Bridge(config, address, say, stop)
    try:
        if not bridge.start():
            return 0
        next_poll = time.monotonic()
        next_stats = next_poll + config.stats_interval
        while not stop.is_set():
            now = time.monotonic()
            if now >= next_poll:
                bridge.poll()
                next_poll = now + config.poll
            bridge.tick()
            if stats_wanted.is_set():
                stats_wanted.clear()
                report(bridge, config, "SIGUSR1")
            if config.stats_interval and now >= next_stats:
                report(bridge, config, "periodic")
                next_stats = now + config.stats_interval
            stop.wait(TICK)
    except Exception as exc:  # noqa: BLE001 - ManagerError, LnError, ZError: one line
        say(f"error: {exc}")
        return 1
    finally:
        try:
            bridge.close()
        finally:
            if bridge.session is not None:
                report(bridge, config, "exit")
    say("stopped")
    return 0


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    try:
        import_zenoh()
    except ZenohMissing:
        print(f"ln_zenoh: error: the Python package zenoh is not installed: {INSTALL_HINT}",
              file=sys.stderr)
        return 1
    try:
        config = build_config(args)
    except ConfigError as exc:
        print(f"ln_zenoh: error: {exc}", file=sys.stderr)
        return 2
    return run(config)


if __name__ == "__main__":
    sys.exit(main())
