"""What `ln_manager -c FILE` adds to a plain manager: the daemons, the scheduler, the
control commands and the console, set up in order and taken down in reverse
(--start-all, --wait-ready, --exit-on-failure, reload)."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from . import routes
from .config import ConfigError, load, model
from .console import Console, stdin_reader
from .control import Control, ControlError
from .core import Core
from .daemons import DaemonPool
from .loggers import Loggers
from .network import Network
from .process_states import ProcState
from .pull import PullTopics
from .scheduler import Scheduler, StartError, Transition

log = logging.getLogger("ln_manager")


class Runner:
    def __init__(self, args: argparse.Namespace, config: model.Config, core: Core,
                 runtime_dir: Path, address: str, shutdown: Callable[[bool], None],
                 stopping: asyncio.Event) -> None:
        self.args = args
        self.shutdown = shutdown
        self.stopping = stopping  # set by SIGTERM/SIGINT/quit: no waiting beyond it
        self.exit_status = 0
        self.pool = DaemonPool(config, args.instance, key_file=args.daemon_key_file,
                               log_dir=runtime_dir)
        self.scheduler = Scheduler(config, core, self.pool.backend(), manager_address=address,
                                   extra_env={"LN_RUNTIME_DIR": str(runtime_dir)})
        self.control = Control(core, self.scheduler, reload=self.reload, shutdown=shutdown)
        self.control.manager_address = address  # the console's topic echo etc. connect here
        self.network: Network | None = None
        if routes.spans_hosts(config, self.pool.local_host):
            self.network = Network(config, core, self.pool, args.instance)
            self.control.network_view = self.network
            self.scheduler.manager_address_for = self._manager_address_for
        local_name = self.network.local_name if self.network is not None else \
            (lambda: self.pool.local_host)
        self.loggers = Loggers(core, lambda: self.pool.link(self.pool.local_host), local_name)
        self.control.loggers = self.loggers
        self.pull = PullTopics(core, config, lambda: self.pool.link(self.pool.local_host),
                               local_name)
        self.control.pull = self.pull
        self.address = address
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

    def _manager_address_for(self, node: str) -> str:
        """LN_MANAGER for a process on `node`: the manager's own address unless that is a
        loopback or wildcard one that another host cannot use; then the manager host's
        address as the network sections say that host reaches it, or, where they give none
        (the manager's host is not in the configuration), the address the manager's
        connection to that node's daemon comes from."""
        host, _, port = self.address.rpartition(":")
        if self.pool.is_local(node) or host.strip("[]") not in ("127.0.0.1", "::1",
                                                                "localhost"):
            return self.address
        assert self.network is not None
        config = self.network.config
        node_host, local = config.node_map.get(node, node), self.network.local_name()
        target = routes.host_address(config, node_host, local)
        if node_host != local and (target is None or target in routes.LOCAL_NAMES):
            target = self.pool.local_address(node)
        if not target:
            return self.address
        return f"[{target}]:{port}" if ":" in target else f"{target}:{port}"

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

    async def reload(self) -> dict[str, Any]:
        defines = dict(item.partition("=")[::2] for item in self.args.define)
        try:
            config = load(self.args.config, defines=defines)
        except ConfigError as exc:
            raise ControlError(f"reload refused, the configuration is unchanged:\n{exc}") \
                from None
        result = self.scheduler.apply_config(config)
        if self.network is not None:
            self.network.config = config  # routes and topic transports of the new file
        await self.loggers.configure(config)  # loggers and topics the new file adds
        self.pull.configure(config)
        return result

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
