"""The composition root of `ln_manager`: builds the manager's objects in dependency order,
each given what it uses through its constructor (nothing is wired in afterwards), runs
them until SIGTERM/SIGINT/`quit` and takes them down in reverse.  frontends/cli.py parses
the command line and calls serve().

Order: the instance's leftovers (segments, service sockets) and the listening socket;
the daemon pool; the core (with the network view of a multi-host configuration, which
needs the core it serves); the scheduler, loggers and pull topics; the control commands;
the web UI; the client server; then runner.py starts what the configuration asks for."""

from __future__ import annotations

import argparse
import asyncio
import logging
import signal
import socket
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from ..addresses import format_address
from .config import model
from .frontends.control import Control
from .loggers.loggers import Loggers
from .network import routes
from .network.hosts import Network
from .network.pull import PullTopics
from .processes.daemon_keys import KeyFileError, read_key_file
from .processes.daemons import DaemonPool
from .processes.scheduler import Scheduler
from .registry.access import Access
from .registry.admission import Admission
from .registry.core import Core, HostRings
from .registry.model import Limits, Registry, RequestError
from .registry.runtime import purge_service_sockets, service_sockets
from .registry.segments import AdoptedRing, Segments, ring_segment_size
from .registry.server import Server, listen_socket
from .registry.service_security import ServiceSecurity
from .registry.services import Services
from .runner import ManagerAddresses, Reload, Runner

if TYPE_CHECKING:
    from .frontends.webui import WebUI

log = logging.getLogger("ln_manager")

WILDCARDS = ("0.0.0.0", "::", "")


def _connect_host(host: str) -> str:
    """Where the manager's own clients connect for a listening address."""
    return "127.0.0.1" if host in WILDCARDS else host


def runner_for(args: argparse.Namespace, config: model.Config, core: Core, pool: DaemonPool,
               network: Network | None, directory: Path, manager_address: str,
               shutdown: Callable[[bool], None], stopping: asyncio.Event) -> Runner:
    """The objects of a manager with a configuration (-c FILE), on `core`, as its Runner."""
    scheduler = Scheduler(config, core, pool.backend(), manager_address=manager_address,
                          extra_env={"LN_RUNTIME_DIR": str(directory)},
                          manager_address_for=ManagerAddresses(manager_address, pool, network)
                          if network is not None else None)
    local_name = network.local_name if network is not None else (lambda: pool.local_host)
    loggers = Loggers(core, lambda: pool.link(pool.local_host), local_name)
    pull = PullTopics(core, config, lambda: pool.link(pool.local_host), local_name)
    control = Control(core, scheduler, reload=Reload(args, scheduler, network, loggers, pull),
                      shutdown=shutdown, loggers=loggers, pull=pull, network_view=network,
                      manager_address=manager_address)  # the console's topic echo etc.
    return Runner(args, pool=pool, scheduler=scheduler, network=network, loggers=loggers,
                  pull=pull, control=control, shutdown=shutdown, stopping=stopping)


def _bare_pool(args: argparse.Namespace, directory: Path, port: int) -> DaemonPool:
    """The daemon pool of a manager without a configuration: its host's ln_daemon (started
    when a logger first needs it) logs the topics, which all have their publishers here."""
    config = model.Config(files=[], instance=model.Instance(
        args.instance, f":{port}", model.Location("<command line>", 0, 0)))
    return DaemonPool(config, args.instance, key_file=args.daemon_key_file, log_dir=directory)


def _leftovers(args: argparse.Namespace, segments: Segments,
               directory: Path) -> tuple[list[AdoptedRing], list[str]] | None:
    """The rings and service sockets a killed predecessor left, to adopt (or removed at
    once with --adopt-window 0); None after printing why they cannot be looked at."""
    adopted: list[AdoptedRing] = []
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
        return None
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
        return None
    return adopted, held_sockets


def _webui(args: argparse.Namespace, control: Control) -> WebUI | None:
    """The web UI of args.webui_plan (docs/webui.md), if one is asked for."""
    if getattr(args, "webui_plan", None) is None:
        return None
    from .frontends.webui import WebUI

    return WebUI(control, args.webui_users, tls=getattr(args, "webui_tls", None))


async def _open_webui(args: argparse.Namespace, webui: WebUI, port: int) -> bool:
    """Listen on the web UI's own port if it has one; print its URL.  False (after saying
    why) if it cannot listen: the manager runs on without it."""
    plan = args.webui_plan
    if plan.port is None:
        host, ui_port = args.host, port
    else:
        try:
            sock = listen_socket(plan.host, plan.port)
        except OSError as exc:
            print(f"ln_manager: error: web UI cannot listen on "
                  f"{format_address((plan.host, plan.port))}: {exc.strerror or exc}",
                  file=sys.stderr)
            return False
        await webui.listen(sock)
        host, ui_port = plan.host, sock.getsockname()[1]
    print(f"ln_manager: web UI on {plan.scheme}://"
          f"{format_address((_connect_host(host), ui_port))}/", flush=True)
    return True


def _admission(instance: str, config: model.Config | None) -> Admission | None:
    """Who may be a client, from the configuration's instance section (docs/security.md);
    None without a configuration (everyone).  KeyFileError or ValueError if its client key
    file or users and groups are unusable."""
    if config is None:
        return None
    inst = config.instance
    key = read_key_file(inst.client_key_file) if inst.client_key_file else None
    return Admission(instance, key, inst.client_uids, inst.client_gids)


async def serve(args: argparse.Namespace, directory: Path,
                config: model.Config | None = None) -> int:
    """Run the manager of args.instance in `directory` (locked by the caller), with the
    processes of `config` if given; its exit status."""
    try:
        admission = _admission(args.instance, config)
    except (KeyFileError, ValueError) as exc:
        print(f"ln_manager: error: {exc}", file=sys.stderr)
        return 1
    segments = Segments(args.instance)
    leftovers = _leftovers(args, segments, directory)
    if leftovers is None:
        return 1
    adopted, held_sockets = leftovers
    try:
        sock = listen_socket(args.host, args.port)
    except OSError as exc:
        print(f"ln_manager: error: cannot listen on "
              f"{format_address((args.host, args.port))}: "
              f"{exc.strerror or exc}", file=sys.stderr)
        return 1
    port = sock.getsockname()[1]
    manager_address = format_address((_connect_host(args.host), port))

    stop = asyncio.Event()
    stop_processes = [True]  # False: leave them running (detach)

    def shutdown(processes: bool) -> None:
        stop_processes[0] = processes
        stop.set()

    pool = DaemonPool(config, args.instance, key_file=args.daemon_key_file,
                      log_dir=directory) if config is not None \
        else _bare_pool(args, directory, port)
    hosts: Callable[[Core], HostRings] | None = None
    if config is not None and routes.spans_hosts(config, pool.local_host):
        def hosts(core: Core) -> HostRings:
            return Network(config, core, pool, args.instance)
    limits = Limits(topics=args.topic_limit, ring_memory=args.ring_memory_limit)
    level = getattr(args, "service_security", None) or (
        config.instance.security if config is not None else None)
    core = Core(args.instance, Registry(ring_segment_size, limits), segments,
                Services(args.service_limit), hosts=hosts,
                service_security=ServiceSecurity.for_instance(level))
    if config is not None:
        core.access = Access(config.access_rules)
    if adopted or held_sockets:
        core.adopt(adopted, directory, held_sockets)
        log.info("adopting %d topic%s and %d service socket%s for %g s", len(adopted),
                 "" if len(adopted) == 1 else "s", len(held_sockets),
                 "" if len(held_sockets) == 1 else "s", args.adopt_window)
    runner: Runner | None = None
    loggers: Loggers | None = None
    if config is not None:
        network = core.hosts if isinstance(core.hosts, Network) else None
        runner = runner_for(args, config, core, pool, network, directory, manager_address,
                            shutdown, stop)
        control = runner.control
    else:
        loggers = Loggers(core, lambda: pool.link(pool.local_host), lambda: pool.local_host)
        control = Control(core, None, shutdown=shutdown, loggers=loggers,
                          manager_address=manager_address)
    webui = _webui(args, control)
    server = Server(core, control=control.handle_json,
                    webui=webui if webui is not None and args.webui_plan.port is None
                    else None, admission=admission)
    loop = asyncio.get_running_loop()
    for signum in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(signum, shutdown, True)
    return await _run(args, sock, core, server, runner, loggers, pool, webui, stop,
                      stop_processes)


async def _run(args: argparse.Namespace, sock: socket.socket, core: Core, server: Server,
               runner: Runner | None, loggers: Loggers | None, pool: DaemonPool,
               webui: WebUI | None, stop: asyncio.Event, stop_processes: list[bool]) -> int:
    """Serve until asked to stop, then take everything down in reverse."""
    port = sock.getsockname()[1]
    await server.start(sock)
    adoption: asyncio.Task[None] | None = None
    if core.adopting:
        async def end_adoption() -> None:
            await asyncio.sleep(args.adopt_window)
            await core.end_adoption()

        adoption = asyncio.get_running_loop().create_task(end_adoption())
    status = 0
    if runner is not None:
        await runner.attach()
    print(f"ln_manager: instance {args.instance} listening on "
          f"{format_address((args.host, port))}", flush=True)
    if loggers is not None:
        loggers.start()
    if webui is not None and not await _open_webui(args, webui, port):
        await webui.close()
        webui = None
    if runner is not None:
        status = await runner.begin()
    if status == 0:
        await stop.wait()
    if runner is not None:
        await runner.end(stop_processes[0])
        status = max(status, runner.exit_status)
    elif loggers is not None:
        await loggers.close(remove=stop_processes[0])
        await pool.close()
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
