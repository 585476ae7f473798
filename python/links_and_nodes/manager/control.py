"""Control commands of a running manager: what the console, `ln_manager status|start|...`
and the scripting API (links_and_nodes.manager.connect) ask for, as JSON objects in CONTROL
frames.  One function per command; each returns a JSON-able dict (docs/process_management.md,
"Control requests")."""

from __future__ import annotations

import asyncio
import json
import logging
import math
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

from .. import logger_files
from . import logger_control
from .core import Core
from .loggers import LoggerError, Loggers
from .scheduler import Scheduler, StartError

log = logging.getLogger("ln_manager")

MAX_OUTPUT_LINES = 10000


class ControlError(Exception):
    """A command that cannot be carried out; the text goes back as {"error": TEXT}, with
    {"code": "ELIMIT"} etc. when an LN_E* name says more than "refused"."""

    def __init__(self, text: str, code: str = "") -> None:
        super().__init__(text)
        self.code = code


class Control:
    def __init__(self, core: Core, scheduler: Scheduler | None,
                 reload: Callable[[], Awaitable[dict[str, Any]]] | None = None,
                 shutdown: Callable[[bool], None] | None = None) -> None:
        self.core = core
        self.scheduler = scheduler
        self._reload = reload
        self._shutdown = shutdown
        self.commands: dict[str, Callable[[dict[str, Any]], Awaitable[dict[str, Any]]]] = {
            "status": self.status, "start": self.start, "stop": self.stop,
            "restart": self.restart, "wait_ready": self.wait_ready, "output": self.output,
            "history": self.history, "topics": self.topics, "services": self.services,
            "reload": self.reload, "quit": self.quit, "detach": self.detach,
            "hosts": self.hosts, "network": self.network,
        }
        self.network_view: Any = None  # network.Network of a multi-host configuration
        self.manager_address: str | None = None  # HOST:PORT, for the console's clients
        from .introspect_control import add_commands

        add_commands(self)  # topic_info, service_info, md_show
        from .event_control import add_commands as add_event_commands

        add_event_commands(self)  # event_connect, events (docs/events.md)
        self.loggers: Loggers | None = None  # set once the manager can reach its daemons
        self.commands.update(logger_control.commands(self._loggers, self._save_logger))

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

    async def handle(self, command: dict[str, Any]) -> dict[str, Any]:
        op = command["op"]
        func = self.commands.get(op)
        if func is None:
            raise ControlError(f"unknown command {op!r}; known: {', '.join(self.commands)}")
        try:
            result = await func(command)
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

    # ---- helpers -------------------------------------------------------------------------
    def _sched(self) -> Scheduler:
        if self.scheduler is None:
            raise ControlError("this manager runs no configuration (start it with -c FILE)")
        return self.scheduler

    @staticmethod
    def _target(command: dict[str, Any]) -> str:
        target = command.get("target", "all")
        if not isinstance(target, str) or not target:
            raise ControlError('"target" must be a process, a group or "all"')
        return target

    @staticmethod
    def _timeout(command: dict[str, Any]) -> float | None:
        timeout = command.get("timeout")
        if timeout is not None and (isinstance(timeout, bool)
                                    or not isinstance(timeout, int | float)
                                    or not math.isfinite(timeout) or timeout < 0):
            raise ControlError('"timeout" must be a number of seconds >= 0 or null')
        return timeout

    @staticmethod
    def _name(command: dict[str, Any], sched: Scheduler) -> str:
        name = command.get("name")
        if not isinstance(name, str) or name not in sched.procs:
            raise ControlError(f"no process named {name!r}")
        return name

    def _loggers(self) -> Loggers:
        if self.loggers is None:
            raise LoggerError("this manager has no loggers (it could not reach its host's "
                              "ln_daemon)", "ENOTFOUND")
        return self.loggers

    async def _save_logger(self, name: str, path: Path) -> dict[str, Any]:
        data = await self._loggers().download(name)
        try:
            return await asyncio.to_thread(logger_files.save, data, path)
        except (OSError, ValueError) as exc:
            raise LoggerError(f"cannot save logger {name!r} to {path}: {exc}") from None

    # ---- commands ------------------------------------------------------------------------
    async def status(self, command: dict[str, Any]) -> dict[str, Any]:
        if self.scheduler is None:
            return {"processes": [], "states": []}
        states = [{"name": name, "up": st.up} for name, st in self.scheduler.states.items()]
        return {"processes": self.scheduler.status(), "states": states}

    async def start(self, command: dict[str, Any]) -> dict[str, Any]:
        return {"processes": self._sched().start(self._target(command))}

    async def stop(self, command: dict[str, Any]) -> dict[str, Any]:
        force = command.get("force", False)
        if not isinstance(force, bool):
            raise ControlError('"force" must be true or false')
        return {"processes": await self._sched().stop(self._target(command), force=force)}

    async def restart(self, command: dict[str, Any]) -> dict[str, Any]:
        return {"processes": await self._sched().restart(self._target(command))}

    async def wait_ready(self, command: dict[str, Any]) -> dict[str, Any]:
        sched = self._sched()
        target = self._target(command)
        try:
            await sched.wait_ready(target, self._timeout(command))
        except TimeoutError:
            waiting = [p["name"] + " (" + p["state"] + ")" for p in sched.status()
                       if p["name"] in sched.targets(target)
                       and p["state"] not in ("ready", "finished")]
            raise ControlError(f"not ready in time: {', '.join(waiting)}") from None
        return {}

    async def output(self, command: dict[str, Any]) -> dict[str, Any]:
        sched = self._sched()
        name = self._name(command, sched)
        n = command.get("n", 100)
        if isinstance(n, bool) or not isinstance(n, int) or not 0 <= n <= MAX_OUTPUT_LINES:
            raise ControlError(f'"n" must be 0..{MAX_OUTPUT_LINES}')
        return {"lines": [{"time": line.time, "stream": line.stream, "text": line.text}
                          for line in sched.output(name, n)]}

    async def history(self, command: dict[str, Any]) -> dict[str, Any]:
        sched = self._sched()
        name = self._name(command, sched)
        return {"transitions": [{"time": t.time, "state": t.state.value, "reason": t.reason}
                                for t in sched.history(name)]}

    async def topics(self, command: dict[str, Any]) -> dict[str, Any]:
        topics = []
        for name, topic in sorted(self.core.registry.topics.items()):
            topics.append({"name": name, "md_name": topic.md_name,
                           "publishers": topic.publishers, "subscribers": topic.subscribers,
                           "published": await self.core.topic_published(name)})
        return {"topics": topics}

    async def services(self, command: dict[str, Any]) -> dict[str, Any]:
        return {"services": self.core.services()}

    async def hosts(self, command: dict[str, Any]) -> dict[str, Any]:
        """Every host of the configuration: daemon state, host id, data port."""
        view = self.network_view
        return {"hosts": view.host_listing() if view is not None else []}

    async def network(self, command: dict[str, Any]) -> dict[str, Any]:
        """Topic streams between hosts with their rates and drops, per host pair too."""
        view = self.network_view
        if view is None:
            return {"streams": [], "pairs": [], "problems": []}
        return view.stream_listing()

    async def reload(self, command: dict[str, Any]) -> dict[str, Any]:
        if self._reload is None:
            raise ControlError("this manager runs no configuration file to reload")
        return await self._reload()

    async def quit(self, command: dict[str, Any]) -> dict[str, Any]:
        if self._shutdown is None:
            raise ControlError("this manager cannot be shut down remotely")
        asyncio.get_running_loop().call_soon(self._shutdown, True)
        return {}

    async def detach(self, command: dict[str, Any]) -> dict[str, Any]:
        """Exit the manager, leaving every process running under its daemon."""
        if self._shutdown is None:
            raise ControlError("this manager cannot be shut down remotely")
        asyncio.get_running_loop().call_soon(self._shutdown, False)
        return {}
