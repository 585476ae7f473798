"""Control commands of a running manager: what the console, `ln_manager status|start|...`,
the scripting API (links_and_nodes.manager.connect) and the web UI ask for, as JSON objects
in CONTROL frames (or WebSocket messages).  The command table (tools/commands/) says which
commands there are and checks their arguments; the process commands' handlers are the
methods here, each returning a JSON-able dict (docs/process_management.md, "Control
requests")."""

from __future__ import annotations

import asyncio
import json
import logging
import weakref
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from ... import logger_files
from ...tools.commands import ArgError, Command, ControlError, Local, check_args, table
from ...tools.commands.from_thread import CONTROL_WAIT, loop_control
from ...tools.commands.local import answer, full_args, strict_json
from ..loggers.loggers import LoggerError, Loggers
from ..processes.scheduler import Scheduler, StartError
from ..registry.core import Core

if TYPE_CHECKING:
    from ..registry.services import Service
    from .commands.event_control import Connection

log = logging.getLogger("ln_manager")


class NetworkView(Protocol):
    """The hosts and topic streams of a multi-host configuration (network.hosts.Network)."""

    def host_listing(self) -> list[dict[str, Any]]: ...
    def stream_listing(self) -> dict[str, Any]: ...


class PullView(Protocol):
    """The pull topics the daemons serve (network.pull.PullTopics)."""

    def listing(self) -> list[dict[str, Any]]: ...
    async def status(self) -> list[dict[str, Any]]: ...


class Control:
    def __init__(self, core: Core, scheduler: Scheduler | None,
                 reload: Callable[[], Awaitable[dict[str, Any]]] | None = None,
                 shutdown: Callable[[bool], None] | None = None, *,
                 loggers: Loggers | None = None, pull: PullView | None = None,
                 network_view: NetworkView | None = None,
                 manager_address: str | None = None) -> None:
        self.core = core
        self.scheduler = scheduler
        self._reload = reload
        self._shutdown = shutdown
        self.pull = pull  # the pull topics of a manager with a configuration
        self.network_view = network_view  # the hosts of a multi-host configuration
        self.manager_address = manager_address  # HOST:PORT, for the console's clients
        self.loggers = loggers  # None: the manager cannot reach its host's daemon
        # the event handlers connected through these commands, by their service
        # (commands/event_control.py)
        self.event_connections: weakref.WeakKeyDictionary[Service, Connection] = \
            weakref.WeakKeyDictionary()

    async def handle_json(self, text: str) -> str:
        """One CONTROL request to its CONTROL_RESULT text."""
        try:
            try:
                command = json.loads(text)
            except RecursionError:
                raise ControlError("command is not JSON: nested too deeply") from None
            if not isinstance(command, dict) or not isinstance(command.get("op"), str):
                raise ControlError('a command is a JSON object with a string "op"')
            result = await self.handle(command)
        except json.JSONDecodeError as exc:
            result = {"ok": False, "error": f"command is not JSON: {exc}"}
        except ControlError as exc:
            result = {"ok": False, "error": str(exc)}
            if exc.code:
                result["code"] = exc.code
        return json.dumps(result)

    @staticmethod
    def describe() -> list[dict[str, Any]]:
        """Every command of the table as JSON (tools/commands/table.py describe())."""
        return table.describe()

    async def handle(self, command: dict[str, Any], session: Any = None) -> dict[str, Any]:
        """Carry out {"op": NAME, ...arguments}: the arguments checked by the table, then
        the command's handler; its result with "ok": true, or ControlError.  `session`: the
        live connection (a WebSocket) for the commands that need one."""
        op = command["op"]
        cmd = table.command(op) if isinstance(op, str) else None
        if cmd is None:
            known = ", ".join(c.name for c in table.commands())
            raise ControlError(f"unknown command {op!r}; known: {known}")
        try:
            if cmd.run is not None:
                return {"ok": True, **await self._run_here(cmd, full_args(cmd, command))}
            args = check_args(cmd, command)
            if cmd.session:
                if session is None:
                    raise ControlError(f"{op} needs a live connection (the web UI's "
                                       "WebSocket)")
                result = await cmd.handler(self, args, session)
            else:
                result = await cmd.handler(self, args)
        except ArgError as exc:
            raise ControlError(str(exc), exc.code) from None
        except (KeyError, StartError) as exc:
            raise ControlError(exc.args[0] if exc.args else str(exc)) from None
        except LoggerError as exc:
            raise ControlError(str(exc), exc.code) from None
        except (ControlError, asyncio.CancelledError):
            raise
        except Exception as exc:  # a bug of ours: answer it, keep the manager running
            log.exception("control command %r failed", op)
            raise ControlError(f"internal error: {exc}") from None
        return {"ok": True, **result}

    async def _run_here(self, cmd: Command, args: dict[str, Any]) -> dict[str, Any]:
        """A command that runs in a client (Command.run), asked for by a JSON request: run in
        a worker thread of the manager with libln clients connected to its own port; one
        that streams is answered with its rows of at most CONTROL_WAIT - 5 seconds."""
        if not self.manager_address:
            raise ControlError("this manager has no address for its own clients")
        loop = asyncio.get_running_loop()
        local = Local(loop_control(self, loop, ControlError), self.manager_address,
                      "ln_manager")
        timer = loop.call_later(CONTROL_WAIT - 5, local.stop.set) if cmd.streams else None

        def work() -> dict[str, Any]:
            try:
                return answer(cmd, local, args)
            finally:
                local.close()  # here: a libln client's goodbye needs the loop

        try:
            return dict(strict_json(await asyncio.to_thread(work)))
        finally:
            if timer is not None:
                timer.cancel()

    # ---- helpers -------------------------------------------------------------------------
    def _sched(self) -> Scheduler:
        if self.scheduler is None:
            raise ControlError("this manager runs no configuration (start it with -c FILE)")
        return self.scheduler

    @staticmethod
    def _name(args: dict[str, Any], sched: Scheduler) -> str:
        name = args["name"]
        if name not in sched.procs:
            raise ControlError(f"no process named {name!r}")
        return name

    def _loggers(self) -> Loggers:
        if self.loggers is None:
            raise LoggerError("this manager has no loggers (it could not reach its host's "
                              "ln_daemon)", "ENOTFOUND")
        return self.loggers

    async def _save_logger(self, name: str, path: Path, encoding: str | None = None
                           ) -> dict[str, Any]:
        data = await self._loggers().download(name)
        try:
            return await asyncio.to_thread(logger_files.save, data, path, encoding)
        except (OSError, ValueError) as exc:
            raise LoggerError(f"cannot save logger {name!r} to {path}: {exc}") from None

    # ---- commands ------------------------------------------------------------------------
    async def status(self, args: dict[str, Any]) -> dict[str, Any]:
        if self.scheduler is None:
            return {"processes": [], "states": []}
        states = [{"name": name, "up": st.up} for name, st in self.scheduler.states.items()]
        return {"processes": self.scheduler.status(), "states": states}

    async def start(self, args: dict[str, Any]) -> dict[str, Any]:
        return {"processes": self._sched().start(args["target"])}

    async def stop(self, args: dict[str, Any]) -> dict[str, Any]:
        return {"processes": await self._sched().stop(args["target"], force=args["force"])}

    async def restart(self, args: dict[str, Any]) -> dict[str, Any]:
        return {"processes": await self._sched().restart(args["target"])}

    async def wait_ready(self, args: dict[str, Any]) -> dict[str, Any]:
        sched = self._sched()
        target = args["target"]
        try:
            await sched.wait_ready(target, args["timeout"])
        except TimeoutError:
            waiting = [p["name"] + " (" + p["state"] + ")" for p in sched.status()
                       if p["name"] in sched.targets(target)
                       and p["state"] not in ("ready", "finished")]
            raise ControlError(f"not ready in time: {', '.join(waiting)}") from None
        return {}

    async def output(self, args: dict[str, Any]) -> dict[str, Any]:
        sched = self._sched()
        name = self._name(args, sched)
        n = args["n"]
        return {"lines": [{"time": line.time, "stream": line.stream, "text": line.text}
                          for line in sched.output(name, n)]}

    async def history(self, args: dict[str, Any]) -> dict[str, Any]:
        sched = self._sched()
        name = self._name(args, sched)
        return {"transitions": [{"time": t.time, "state": t.state.value, "reason": t.reason}
                                for t in sched.history(name)]}

    async def topics(self, args: dict[str, Any]) -> dict[str, Any]:
        topics = []
        for name, topic in sorted(self.core.registry.topics.items()):
            topics.append({"name": name, "md_name": topic.md_name,
                           "publishers": topic.publishers, "subscribers": topic.subscribers,
                           "published": await self.core.topic_published(name)})
        return {"topics": topics}

    async def services(self, args: dict[str, Any]) -> dict[str, Any]:
        return {"services": self.core.services()}

    async def hosts(self, args: dict[str, Any]) -> dict[str, Any]:
        """Every host of the configuration: daemon state, host id, data port."""
        view = self.network_view
        return {"hosts": view.host_listing() if view is not None else []}

    async def network(self, args: dict[str, Any]) -> dict[str, Any]:
        """Topic streams between hosts with their rates and drops, per host pair too, and
        the pull producers' counters per host ("pull")."""
        view = self.network_view
        result = view.stream_listing() if view is not None else \
            {"streams": [], "pairs": [], "problems": []}
        return {**result, "pull": await self.pull.status() if self.pull is not None else []}

    async def pull_topics(self, args: dict[str, Any]) -> dict[str, Any]:
        """The pull topics served by the daemons: NDN name, port, host (docs/pull.md)."""
        return {"topics": self.pull.listing() if self.pull is not None else []}

    async def reload(self, args: dict[str, Any]) -> dict[str, Any]:
        if self._reload is None:
            raise ControlError("this manager runs no configuration file to reload")
        return await self._reload()

    async def quit(self, args: dict[str, Any]) -> dict[str, Any]:
        if self._shutdown is None:
            raise ControlError("this manager cannot be shut down remotely")
        asyncio.get_running_loop().call_soon(self._shutdown, True)
        return {}

    async def detach(self, args: dict[str, Any]) -> dict[str, Any]:
        """Exit the manager, leaving every process running under its daemon."""
        if self._shutdown is None:
            raise ControlError("this manager cannot be shut down remotely")
        asyncio.get_running_loop().call_soon(self._shutdown, False)
        return {}
