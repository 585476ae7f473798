"""`ln_manager`: runs the manager of one instance.  Takes the instance lock, removes
segments and service sockets a killed predecessor's clients left behind, serves clients
until SIGTERM/SIGINT, then closes every connection and unlinks every segment of the
instance."""

from __future__ import annotations

import argparse
import asyncio
import logging
import signal
import sys
from pathlib import Path

from .registry import Limits, RequestError
from .runtime import (
    InstanceLock,
    RuntimeDirError,
    prepare,
    purge_service_sockets,
    runtime_dir,
)
from .services import DEFAULT_LIMIT as SERVICE_LIMIT
from .services import Services

log = logging.getLogger("ln_manager")

MAX_INSTANCE = 200  # bytes; keeps segment names well below NAME_MAX
LOG_LEVELS = ("debug", "info", "warning", "error")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ln_manager",
        description="Run the links_and_nodes manager of one instance: the registry of its "
                    "clients, topics and their shared-memory segments.")
    parser.add_argument("--port", type=int, required=True,
                        help="TCP port for clients; 0 picks a free one (printed when ready)")
    parser.add_argument("--instance", required=True,
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
    parser.add_argument("--log-level", choices=LOG_LEVELS, default="info",
                        help="least severe log messages shown on stderr (default info)")
    return parser


def _check_args(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
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


def _address(host: str, port: int) -> str:
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


async def _serve(args: argparse.Namespace, directory: Path) -> int:
    # libln is loaded only here, so --help and argument errors work without it.
    from .core import Core
    from .registry import Registry
    from .segments import Segments, ring_segment_size
    from .server import Server, listen_socket

    segments = Segments(args.instance)
    try:
        purged = segments.purge()
    except RequestError as exc:
        print(f"ln_manager: error: {exc.text}", file=sys.stderr)
        return 1
    if purged:
        log.info("removed %d stale segment%s of instance %r", purged,
                 "" if purged == 1 else "s", args.instance)
    try:
        sockets = purge_service_sockets(directory)
    except OSError as exc:
        print(f"ln_manager: error: cannot list runtime directory {directory}: "
              f"{exc.strerror or exc}", file=sys.stderr)
        return 1
    if sockets:
        log.info("removed %d stale service socket%s in %s: %s", len(sockets),
                 "" if len(sockets) == 1 else "s", directory, ", ".join(sockets))
    limits = Limits(topics=args.topic_limit, ring_memory=args.ring_memory_limit)
    core = Core(args.instance, Registry(ring_segment_size, limits), segments,
                Services(args.service_limit))
    try:
        sock = listen_socket(args.host, args.port)
    except OSError as exc:
        print(f"ln_manager: error: cannot listen on {_address(args.host, args.port)}: "
              f"{exc.strerror or exc}", file=sys.stderr)
        return 1
    port = sock.getsockname()[1]
    server = Server(core)
    await server.start(sock)
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for signum in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(signum, stop.set)
    print(f"ln_manager: instance {args.instance} listening on {_address(args.host, port)}",
          flush=True)
    await stop.wait()
    log.info("shutting down: closing %d client%s", len(core.registry.clients),
             "" if len(core.registry.clients) == 1 else "s")
    await server.close()
    removed = core.shutdown()
    log.info("removed %d segment%s, exiting", removed, "" if removed == 1 else "s")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    _check_args(parser, args)
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
        return asyncio.run(_serve(args, directory))
    finally:
        lock.release()


if __name__ == "__main__":
    sys.exit(main())
