"""`ln_manager`: runs the manager of one instance.  Takes the instance lock, adopts the
segments and service sockets a killed predecessor left (for the clients that reconnect
within the adoption window; the rest is removed after it), serves clients
until SIGTERM/SIGINT (or `quit`), then closes every connection and unlinks every segment
of the instance.  With `-c FILE` it also runs the configuration's processes through the
ln_daemons (scheduler.py) with a console on stdin; `ln_manager status|start|stop|...`
talk to a running manager instead (remote_cli.py); `ln_manager check FILE` only
validates a configuration (check.py)."""

from __future__ import annotations

import argparse
import asyncio
import logging
import signal
import sys
from pathlib import Path
from typing import Any

from . import remote_cli
from .registry import Limits, RequestError
from .runtime import (
    InstanceLock,
    RuntimeDirError,
    prepare,
    purge_service_sockets,
    runtime_dir,
    service_sockets,
)
from .services import DEFAULT_LIMIT as SERVICE_LIMIT
from .services import Services

log = logging.getLogger("ln_manager")

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
    parser.add_argument("--topic-limit", type=int, default=Limits.topics, metavar="N",
                        help=f"most topics at a time (default {Limits.topics})")
    parser.add_argument("--ring-memory-limit", type=int, default=Limits.ring_memory,
                        metavar="BYTES",
                        help=f"most bytes of one topic's ring (default {Limits.ring_memory})")
    parser.add_argument("--service-limit", type=int, default=SERVICE_LIMIT, metavar="N",
                        help=f"most services at a time (default {SERVICE_LIMIT})")
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


def _address(host: str, port: int) -> str:
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


async def _serve(args: argparse.Namespace, directory: Path, config: Any = None) -> int:
    # libln is loaded only here, so --help and argument errors work without it.
    from .core import Core
    from .registry import Registry
    from .segments import Segments, ring_segment_size
    from .server import Server, listen_socket

    segments = Segments(args.instance)
    adopted: list[Any] = []
    held_sockets: list[str] = []
    try:
        if args.adopt_window > 0:
            adopted, removed = segments.adopt()
            for name, reason in removed:
                log.warning("removed segment %s instead of adopting it: %s", name, reason)
        else:
            purged = segments.purge()
            if purged:
                log.info("removed %d stale segment%s of instance %r", purged,
                         "" if purged == 1 else "s", args.instance)
    except RequestError as exc:
        print(f"ln_manager: error: {exc.text}", file=sys.stderr)
        return 1
    try:
        if args.adopt_window > 0:
            held_sockets = service_sockets(directory)
        else:
            sockets = purge_service_sockets(directory)
            if sockets:
                log.info("removed %d stale service socket%s in %s: %s", len(sockets),
                         "" if len(sockets) == 1 else "s", directory, ", ".join(sockets))
    except OSError as exc:
        print(f"ln_manager: error: cannot list runtime directory {directory}: "
              f"{exc.strerror or exc}", file=sys.stderr)
        return 1
    limits = Limits(topics=args.topic_limit, ring_memory=args.ring_memory_limit)
    core = Core(args.instance, Registry(ring_segment_size, limits), segments,
                Services(args.service_limit))
    if adopted or held_sockets:
        core.adopt(adopted, directory, held_sockets)
        log.info("adopting %d topic%s and %d service socket%s for %g s", len(adopted),
                 "" if len(adopted) == 1 else "s", len(held_sockets),
                 "" if len(held_sockets) == 1 else "s", args.adopt_window)
    try:
        sock = listen_socket(args.host, args.port)
    except OSError as exc:
        print(f"ln_manager: error: cannot listen on {_address(args.host, args.port)}: "
              f"{exc.strerror or exc}", file=sys.stderr)
        return 1
    port = sock.getsockname()[1]
    server = Server(core)
    await server.start(sock)
    adoption: asyncio.Task[None] | None = None
    if core.adopting:
        async def end_adoption() -> None:
            await asyncio.sleep(args.adopt_window)
            await core.end_adoption()

        adoption = asyncio.get_running_loop().create_task(end_adoption())
    stop = asyncio.Event()
    stop_processes = [True]  # False: leave them running (detach)

    def shutdown(processes: bool) -> None:
        stop_processes[0] = processes
        stop.set()

    loop = asyncio.get_running_loop()
    for signum in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(signum, shutdown, True)
    runner = None
    status = 0
    if config is not None:
        from .runner import Runner

        connect_host = "127.0.0.1" if args.host in ("0.0.0.0", "::", "") else args.host
        runner = Runner(args, config, core, directory, _address(connect_host, port), shutdown,
                        stop)
        server.control = runner.control.handle_json
        await runner.attach()
    print(f"ln_manager: instance {args.instance} listening on {_address(args.host, port)}",
          flush=True)
    webui = None
    if runner is not None:
        webui = await _start_webui(args, runner.control, server, port)
        status = await runner.begin()
    else:
        from .control import Control

        control = Control(core, None, shutdown=shutdown)
        control.loggers, bare_pool = _bare_loggers(args, core, directory, port)
        control.loggers.start()
        server.control = control.handle_json
        control.manager_address = _address(
            "127.0.0.1" if args.host in ("0.0.0.0", "::", "") else args.host, port)
        webui = await _start_webui(args, control, server, port)
    if status == 0:
        await stop.wait()
    if runner is not None:
        await runner.end(stop_processes[0])
        status = max(status, runner.exit_status)
    else:
        await control.loggers.close(remove=stop_processes[0])
        await bare_pool.close()
    log.info("shutting down: closing %d client%s", len(core.registry.clients),
             "" if len(core.registry.clients) == 1 else "s")
    if adoption is not None:
        adoption.cancel()
    if webui is not None:
        await webui.close()
    await server.close()
    removed = await core.shutdown()
    if runner is not None:
        await runner.finish()
    log.info("removed %d segment%s, exiting", removed, "" if removed == 1 else "s")
    return status


async def _start_webui(args: argparse.Namespace, control: Any, server: Any, port: int) -> Any:
    """The web UI of args.webui_plan (docs/webui.md) on the manager's port or its own;
    prints its URL."""
    from .webui import WebUI

    plan = getattr(args, "webui_plan", None)
    if plan is None:
        return None
    webui = WebUI(control, args.webui_users)
    if plan.port is None:
        server.webui = webui
        host, ui_port = args.host, port
    else:
        from .server import listen_socket

        try:
            sock = listen_socket(plan.host, plan.port)
        except OSError as exc:
            print(f"ln_manager: error: web UI cannot listen on "
                  f"{_address(plan.host, plan.port)}: {exc.strerror or exc}", file=sys.stderr)
            await webui.close()
            return None
        await webui.listen(sock)
        host, ui_port = plan.host, sock.getsockname()[1]
    shown = "127.0.0.1" if host in ("0.0.0.0", "::", "") else host
    print(f"ln_manager: web UI on http://{_address(shown, ui_port)}/", flush=True)
    return webui


def _webui_plan(args: argparse.Namespace, config: Any) -> None:
    """args.webui_plan and args.webui_users from the options; exit 2 if they are wrong."""
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


def _bare_loggers(args: argparse.Namespace, core: Any, directory: Path, port: int) -> Any:
    """Loggers of a manager without a configuration: its host's ln_daemon (started when a
    logger first needs it) logs the topics, which all have their publishers here."""
    from .config import model
    from .daemons import DaemonPool
    from .loggers import Loggers

    config = model.Config(files=[], instance=model.Instance(
        args.instance, f":{port}", model.Location("<command line>", 0, 0)))
    pool = DaemonPool(config, args.instance, key_file=args.daemon_key_file, log_dir=directory)
    return Loggers(core, lambda: pool.link(pool.local_host), lambda: pool.local_host), pool


def _load_config(parser: argparse.ArgumentParser, args: argparse.Namespace) -> Any:
    """Read -c FILE (exit 2 with every error on failure) and fill --instance/--port/--host
    from its instance section where the command line did not give them."""
    from .check import parse_defines
    from .config import ConfigError, load

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
    host, _, port = config.instance.manager.rpartition(":")
    if args.port is None:
        if not port.isdigit():
            parser.error(f"{config.instance.location}: manager {config.instance.manager!r} "
                         "has no port")
        args.port = int(port)
    if host.strip("[]") and args.host == "127.0.0.1":
        args.host = host.strip("[]")
    elif not host.strip("[]") and args.host == "127.0.0.1" and _spans_hosts(config):
        # clients on the other hosts must reach the manager
        args.host = "0.0.0.0"
    return config


def _spans_hosts(config: Any) -> bool:
    """True if the configuration names a host other than this one (see runner.py)."""
    import socket

    from .routes import spans_hosts

    return spans_hosts(config, socket.gethostname())


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] == "check":
        from . import check

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
    logging.basicConfig(stream=sys.stderr, level=args.log_level.upper(),
                        format="%(asctime)s ln_manager %(levelname)s: %(message)s")
    try:
        from .segments import sanitize_instance  # the same name in /dev/shm and on disk

        directory = prepare(runtime_dir(sanitize_instance(args.instance)))
        lock = InstanceLock(directory, args.instance)
        lock.acquire()
    except ImportError as exc:
        print(f"ln_manager: error: cannot load libln: {exc}", file=sys.stderr)
        return 1
    except RuntimeDirError as exc:
        print(f"ln_manager: error: {exc}", file=sys.stderr)
        return 1
    try:
        return asyncio.run(_serve(args, directory, config))
    finally:
        lock.release()


if __name__ == "__main__":
    sys.exit(main())
