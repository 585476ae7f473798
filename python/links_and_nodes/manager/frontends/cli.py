"""`ln_manager`: runs the manager of one instance.  Takes the instance lock, adopts the
segments and service sockets a killed predecessor left (for the clients that reconnect
within the adoption window; the rest is removed after it), serves clients
until SIGTERM/SIGINT (or `quit`), then closes every connection and unlinks every segment
of the instance.  With `-c FILE` it also runs the configuration's processes through the
ln_daemons (scheduler.py) with a console on stdin; `ln_manager status|start|stop|...`
talk to a running manager instead (remote_cli.py); `ln_manager check FILE` only
validates a configuration (config_check.py).  This module reads the command line; app.py
builds the manager's objects and runs them.  Reading the command line loads little: what
a launch, a check or a remote command needs is imported once it is known to be wanted
(tests/python/manager/test_cli_imports.py keeps it so)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from ... import __version__
from ..registry.defaults import RING_MEMORY_LIMIT, SERVICE_LIMIT, TOPIC_LIMIT
from . import remote_cli

MAX_INSTANCE = 200  # bytes; keeps segment names well below NAME_MAX
ADOPT_WINDOW = 5.0  # seconds reconnecting clients have to take back what they held
LOG_LEVELS = ("debug", "info", "warning", "error")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ln_manager",
        description="Run the links_and_nodes manager of one instance: the registry of its "
                    "clients, topics and their shared-memory segments, and with -c the "
                    "processes of a configuration file.  `ln_manager COMMAND --help` for "
                    "the commands that talk to a running manager: "
                    + ", ".join(remote_cli.names()) + " "
                    "(`ln_manager topic echo|hz|bw|info`, `md show`, `service call`: "
                    "docs/introspection.md; `ln_manager param ...`: docs/parameters.md); "
                    "`ln_manager check FILE.lnc` validates a configuration without "
                    "starting anything; `ln_manager webui-passwd USER` prints a line for "
                    "the web UI's auth file (docs/webui.md).")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}",
                        help="print the version of links_and_nodes (ln.h's LN_VERSION_*) "
                             "and exit")
    parser.add_argument("-c", "--config", metavar="FILE",
                        help="configuration (.lnc) whose processes this manager runs; its "
                             "instance section gives --instance and --port")
    parser.add_argument("-D", "--define", action="append", default=[], metavar="NAME=VALUE",
                        help="a define for the configuration (repeatable)")
    parser.add_argument("--strict", action="store_true",
                        help="treat the configuration's warnings as errors")
    parser.add_argument("--start-all", action="store_true",
                        help="start every process of the configuration")
    parser.add_argument("--wait-ready", action="store_true",
                        help="with --start-all: print 'all ready' once every process is "
                             "ready")
    parser.add_argument("--ready-timeout", type=float, default=None, metavar="SECONDS",
                        help="with --wait-ready: give up after this long")
    parser.add_argument("--exit-on-failure", action="store_true",
                        help="stop everything and exit 1 if a process fails to start "
                             "(or does not get ready within --ready-timeout)")
    parser.add_argument("--no-console", action="store_true",
                        help="do not read commands from stdin")
    parser.add_argument("--daemon-key-file", type=Path, default=None, metavar="FILE",
                        help="the ln_daemon key (default $LN_DAEMON_KEY_FILE or "
                             "~/.config/links_and_nodes/daemon.key, created if missing)")
    parser.add_argument("--port", type=int, default=None,
                        help="TCP port for clients; 0 picks a free one (printed when ready)")
    parser.add_argument("--instance", default=None,
                        help="instance name; one manager per instance and host")
    parser.add_argument("--host", default="127.0.0.1",
                        help="address to listen on (default 127.0.0.1; 0.0.0.0 or :: for "
                             "every interface)")
    parser.add_argument("--topic-limit", type=int, default=TOPIC_LIMIT, metavar="N",
                        help=f"most topics at a time (default {TOPIC_LIMIT})")
    parser.add_argument("--ring-memory-limit", type=int, default=RING_MEMORY_LIMIT,
                        metavar="BYTES",
                        help=f"most bytes of one topic's ring (default {RING_MEMORY_LIMIT})")
    parser.add_argument("--service-limit", type=int, default=SERVICE_LIMIT, metavar="N",
                        help=f"most services at a time (default {SERVICE_LIMIT})")
    parser.add_argument("--service-security", choices=("none", "authenticate", "encrypt"),
                        default=None,
                        help="how service calls between hosts are protected (default: the "
                             "instance's `security:`, else authenticate; docs/security.md)")
    parser.add_argument("--adopt-window", type=float, default=ADOPT_WINDOW, metavar="SECONDS",
                        help="after a restart, how long the rings and service sockets a "
                             "killed predecessor left are kept for the clients that reconnect "
                             f"(default {ADOPT_WINDOW:g}; 0 removes them at once)")
    parser.add_argument("--log-level", choices=LOG_LEVELS, default="info",
                        help="least severe log messages shown on stderr (default info)")
    from .webui import add_arguments as add_webui_arguments

    add_webui_arguments(parser)  # --webui, --webui-port, --webui-host (docs/webui.md)
    return parser


def _check_args(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    if args.instance is None or args.port is None:
        parser.error("--port and --instance are required without -c FILE")
    size = len(args.instance.encode("utf-8"))
    if not 1 <= size <= MAX_INSTANCE or not args.instance.isprintable():
        parser.error(f"--instance must be 1..{MAX_INSTANCE} bytes of printable characters")
    if not 0 <= args.port <= 65535:
        parser.error(f"--port {args.port} is not a TCP port")
    if args.topic_limit < 1:
        parser.error("--topic-limit must be at least 1")
    if args.ring_memory_limit < 1:
        parser.error("--ring-memory-limit must be positive")
    if args.service_limit < 1:
        parser.error("--service-limit must be at least 1")
    if not 0 <= args.adopt_window <= 3600:
        parser.error("--adopt-window must be 0..3600 seconds")


def _webui_plan(args: argparse.Namespace, config: Any) -> None:
    """args.webui_plan, args.webui_users and args.webui_tls (its SSLContext) from the
    options; exit 2 if they are wrong, 1 if the TLS certificate or key cannot be used."""
    from .webui import WebUIError, plan
    from .webui.auth import AuthFileError, load_auth_file

    try:
        args.webui_plan = plan(args, config)
        args.webui_users = None
        if args.webui_plan is not None and args.webui_plan.auth_file is not None:
            args.webui_users = load_auth_file(args.webui_plan.auth_file)
    except (WebUIError, AuthFileError) as exc:
        print(f"ln_manager: error: {exc}", file=sys.stderr)
        sys.exit(2)
    args.webui_tls = None
    if args.webui_plan is not None and args.webui_plan.tls_cert is not None:
        from .webui.tls import TLSError, server_context

        try:
            args.webui_tls = server_context(args.webui_plan.tls_cert, args.webui_plan.tls_key)
        except TLSError as exc:
            print(f"ln_manager: error: {exc}", file=sys.stderr)
            sys.exit(1)
    if args.webui_plan is not None and args.webui_plan.warning:
        print(f"ln_manager: warning: {args.webui_plan.warning}", file=sys.stderr)


def _load_config(parser: argparse.ArgumentParser, args: argparse.Namespace) -> Any:
    """Read -c FILE (exit 2 with every error on failure) and fill --instance/--port/--host
    from its instance section where the command line did not give them."""
    from ...addresses import AddressError, parse_address
    from ..config import ConfigError, load
    from .config_check import parse_defines

    defines = parse_defines(parser, args.define)
    try:
        config = load(args.config, defines=defines, strict=args.strict)
    except ConfigError as exc:
        print(str(exc), file=sys.stderr)
        print(f"ln_manager: {args.config}: configuration has errors, nothing started",
              file=sys.stderr)
        sys.exit(2)
    except OSError as exc:
        parser.error(f"cannot read {args.config}: {exc.strerror or exc}")
    except ValueError as exc:  # a bad -D name
        parser.error(str(exc))
    for w in config.warnings:
        print(f"{w.location}: warning: {w.message}", file=sys.stderr)
    if args.instance is None:
        args.instance = config.instance.name
    try:
        host, port = parse_address(config.instance.manager, default_host="")
    except AddressError as exc:
        parser.error(f"{config.instance.location}: manager: {exc}")
    if args.port is None:
        args.port = port
    if host and args.host == "127.0.0.1":
        args.host = host
    elif not host and args.host == "127.0.0.1" and _spans_hosts(config):
        # clients on the other hosts must reach the manager
        args.host = "0.0.0.0"
    return config


def _spans_hosts(config: Any) -> bool:
    """True if the configuration names a host other than this one (see runner.py)."""
    import socket

    from ..network.routes import spans_hosts

    return spans_hosts(config, socket.gethostname())


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] == "check":
        from . import config_check as check

        return check.main(argv[1:])
    if argv and argv[0] in remote_cli.names():  # the command table (commands/)
        return remote_cli.main(argv)
    if argv and argv[0] == "webui-passwd":  # a line for the web UI's auth file
        from .webui.auth import passwd_main

        return passwd_main(argv[1:])
    parser = build_parser()
    args = parser.parse_args(argv)
    config = _load_config(parser, args) if args.config else None
    _check_args(parser, args)
    _webui_plan(args, config)
    return _serve(args, config)


def _serve(args: argparse.Namespace, config: Any) -> int:
    """Take the instance lock and run the manager until it is asked to stop."""
    import asyncio
    import logging
    import signal

    from ...naming import runtime_dir
    from ..registry.runtime import InstanceLock, RuntimeDirError, prepare

    logging.basicConfig(stream=sys.stderr, level=args.log_level.upper(),
                        format="%(asctime)s ln_manager %(levelname)s: %(message)s")
    try:
        from ..registry import segments  # noqa: F401  (loads libln: fail here if it cannot)

        directory = prepare(runtime_dir(args.instance))
        lock = InstanceLock(directory, args.instance)
        lock.acquire()
    except ImportError as exc:
        print(f"ln_manager: error: cannot load libln: {exc}", file=sys.stderr)
        return 1
    except RuntimeDirError as exc:
        print(f"ln_manager: error: {exc}", file=sys.stderr)
        return 1
    try:
        from ..app import serve  # the composition root; loads libln

        return asyncio.run(serve(args, directory, config))
    finally:
        # Everything is down once the loop has ended, and it put the default handlers back: a
        # SIGTERM/SIGINT now (asked to stop while stopping) must not turn this clean exit
        # into a death by signal.
        for signum in (signal.SIGTERM, signal.SIGINT):
            signal.signal(signum, signal.SIG_IGN)
        lock.release()


if __name__ == "__main__":
    sys.exit(main())
