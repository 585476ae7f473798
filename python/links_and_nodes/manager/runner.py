"""What `ln_manager -c FILE` adds to a plain manager: the daemons, the scheduler, the
control commands and the console, started in order and taken down in reverse
(--start-all, --wait-ready, --exit-on-failure, reload).  app.py builds the objects and
gives them to Runner; ManagerAddresses and Reload are what it gives the scheduler and the
control commands."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import sys
from collections.abc import Callable
from typing import Any

from ..addresses import format_address, is_loopback, parse_address
from ..tools.commands import ControlError
from .config import ConfigError, load
from .frontends.console import Console, stdin_reader
from .frontends.control import Control
from .loggers.loggers import Loggers
from .network import routes
from .network.hosts import Network
from .network.pull import PullTopics
from .processes.daemons import DaemonPool
from .processes.scheduler import Scheduler, StartError, Transition
from .processes.states import ProcState

log = logging.getLogger("ln_manager")


class ManagerAddresses:
    """LN_MANAGER for a process on a node (Scheduler's manager_address_for) of a
    configuration spanning several hosts."""

    def __init__(self, address: str, pool: DaemonPool, network: Network) -> None:
        self.address = address
        self.pool = pool
        self.network = network

    def __call__(self, node: str) -> str:
        """The manager's own address unless that is a loopback or wildcard one that
        another host cannot use; then the manager host's address as the network sections
        say that host reaches it, or, where they give none (the manager's host is not in
        the configuration), the address the manager's connection to that node's daemon
        comes from."""
        host, port = parse_address(self.address, default_host="")
        if self.pool.is_local(node) or not is_loopback(host):
            return self.address
        config = self.network.config
        node_host, local = config.node_map.get(node, node), self.network.local_name()
        target = routes.host_address(config, node_host, local)
        if node_host != local and (target is None or target in routes.LOCAL_NAMES):
            target = self.pool.local_address(node)
        if not target:
            return self.address
        return format_address((target, port))


class Reload:
    """The `reload` command: reads the configuration file again (with the command line's
    defines) and hands it to whatever follows it."""

    def __init__(self, args: argparse.Namespace, scheduler: Scheduler,
                 network: Network | None, loggers: Loggers, pull: PullTopics) -> None:
        self.args = args
        self.scheduler = scheduler
        self.network = network
        self.loggers = loggers
        self.pull = pull

    async def __call__(self) -> dict[str, Any]:
        defines = dict(item.partition("=")[::2] for item in self.args.define)
        try:
            config = load(self.args.config, defines=defines)
        except ConfigError as exc:
            raise ControlError(f"reload refused, the configuration is unchanged:\n{exc}") \
                from None
        result = self.scheduler.apply_config(config)
        if self.network is not None:
            self.network.configure(config)  # routes and topic transports of the new file
        await self.loggers.configure(config)  # loggers and topics the new file adds
        self.pull.configure(config)
        return result


class Runner:
    def __init__(self, args: argparse.Namespace, *, pool: DaemonPool, scheduler: Scheduler,
                 network: Network | None, loggers: Loggers, pull: PullTopics,
                 control: Control, shutdown: Callable[[bool], None],
                 stopping: asyncio.Event) -> None:
        self.args = args
        self.shutdown = shutdown
        self.stopping = stopping  # set by SIGTERM/SIGINT/quit: no waiting beyond it
        self.exit_status = 0
        self.pool = pool
        self.scheduler = scheduler
        self.network = network
        self.loggers = loggers
        self.pull = pull
        self.control = control
        self._console: asyncio.Task[None] | None = None
        if args.exit_on_failure:
            self.scheduler.transition_listeners.append(self._fail_fast)

    async def attach(self) -> None:
        """Take over what the daemons still run for this instance (before clients come)."""
        if self.network is not None:
            self.network.start()
        await self.scheduler.attach()
        if await self._local_daemon_runs():  # never start one just to look
            await self.loggers.adopt()
            await self.pull.adopt()
        self.loggers.start()
        self.pull.start()
        await self.loggers.configure(self.scheduler.config)

    async def _local_daemon_runs(self) -> bool:
        host, port = self.pool.address(self.pool.local_host)
        try:
            _, writer = await asyncio.wait_for(asyncio.open_connection(host, port), 1.0)
        except (OSError, TimeoutError):
            return False
        writer.close()
        return True

    async def begin(self) -> int:
        """Start what was asked, open the console; non-zero if the manager must exit right
        away (--exit-on-failure)."""
        if self.stopping.is_set():  # SIGTERM/SIGINT while attaching: on to the end
            return self.exit_status
        if self.args.start_all:
            self.scheduler.start("all")
        if not self.args.no_console:
            self._console = asyncio.get_running_loop().create_task(self._run_console())
        if self.args.wait_ready:
            try:
                if not await self._unless_stopping(
                        self.scheduler.wait_ready("all", self.args.ready_timeout,
                                                  final=True)):
                    return 0  # asked to stop while waiting
            except (StartError, TimeoutError) as exc:
                text = str(exc) or "not ready within --ready-timeout"
                print(f"ln_manager: not all processes ready: {text}", flush=True)
                if self.args.exit_on_failure:
                    self.exit_status = 1
                    return 1
            else:
                print(f"ln_manager: all {len(self.scheduler.procs)} processes ready",
                      flush=True)
        return self.exit_status

    async def _unless_stopping(self, awaitable: Any) -> bool:
        """Await `awaitable` unless the manager is asked to stop first; False then."""
        task = asyncio.ensure_future(awaitable)
        stop = asyncio.ensure_future(self.stopping.wait())
        done, _ = await asyncio.wait({task, stop}, return_when=asyncio.FIRST_COMPLETED)
        if task in done:
            stop.cancel()
            task.result()  # its exception, if any
            return True
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError, StartError, TimeoutError):
            await task
        return False

    def _fail_fast(self, name: str, t: Transition) -> None:
        if t.state == ProcState.FAILED:
            # decided once the scheduler has scheduled its restart, if it restarts
            asyncio.get_running_loop().call_soon(self._failed_for_good, name)

    def _failed_for_good(self, name: str) -> None:
        rt = self.scheduler.procs.get(name)
        if rt is None or rt.state != ProcState.FAILED or self.exit_status:
            return
        if rt.restart_task is not None and not rt.restart_task.done():
            return  # by its restart policy, or its watchdog's restart
        print(f"ln_manager: process {name} failed: {rt.reason}", flush=True)
        self.exit_status = 1
        self.shutdown(True)

    async def _run_console(self) -> None:
        try:
            await Console(self.control).run(await stdin_reader())
        except (OSError, ValueError) as exc:  # no usable stdin: run without a console
            log.info("no console: %s", exc)

    async def end(self, stop_processes: bool) -> None:
        if self._console is not None:
            self._console.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._console
        await self.loggers.close(remove=stop_processes)  # detached: the samples stay
        await self.pull.close(remove=stop_processes)  # detached: still served
        if stop_processes:
            log.info("stopping every process")
            await self.scheduler.shutdown()
        else:
            log.info("detaching: processes keep running under their daemons")
            await self.scheduler.close()
        sys.stdout.flush()

    async def finish(self) -> None:
        """Close the daemon links, after the core released every ring (remote ones go
        through them)."""
        if self.network is not None:
            await self.network.close()
        await self.pool.close()
