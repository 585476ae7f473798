"""The manager scripting API: `links_and_nodes.manager.connect("HOST:PORT")` returns a
connection to a running ln_manager whose methods start, stop and watch the processes of
its configuration (CONTROL requests, docs/process_management.md).  Blocking and
single-threaded; speaks the manager protocol with protocol.py's codec, needs no libln.

    mgr = connect("localhost:54414")
    mgr.start("arm")
    mgr.wait_ready("arm", timeout=30)
    print(mgr.state("arm/sensor"), mgr.output("arm/sensor", 20))
"""

from __future__ import annotations

import json
import os
import socket
from typing import Any

from ..addresses import parse_manager_address
from . import client_key
from . import protocol as p
from .commands import ControlError, Local, ManagerError, commands
from .commands import command as command_entry
from .commands.script_methods import add_methods, method
from .framing import receive

DEFAULT_TIMEOUT = 10.0  # seconds for connecting and for answers that do not wait


class Manager:
    """One connection to a manager (use as a context manager or call close()); its methods
    are the commands of the table, those that run in the client (topic_echo, param_set, ...)
    in this process with what local() keeps (one libln client for the parameter blocks)."""

    _local: Local | None = None

    def __init__(self, address: str, *, timeout: float = DEFAULT_TIMEOUT,
                 name: str = "ln_script") -> None:
        host, port = parse_manager_address(address)
        self.address = address
        self.timeout = timeout
        try:
            self._sock = socket.create_connection((host, port), timeout=timeout)
        except OSError as exc:
            raise ManagerError(f"cannot reach the manager at {address}: "
                               f"{exc.strerror or exc}") from None
        self._next_id = 0
        self._sock.settimeout(timeout)
        try:
            welcome = client_key.greet(self._sock, name, ManagerError)
        except ManagerError as exc:
            self.close()
            raise ManagerError(f"manager {address}: {exc}") from None
        except TimeoutError:
            self.close()
            raise ManagerError("no answer from the manager in time") from None
        except OSError as exc:
            self.close()
            raise ManagerError(f"connection to the manager lost: {exc}") from None
        if isinstance(welcome, p.Error):
            self.close()
            raise ManagerError(f"the manager refused the connection: {welcome.text}")
        if not isinstance(welcome, p.Welcome):
            self.close()
            raise ManagerError(f"the manager answered HELLO with {welcome.TYPE.name}")
        self.instance = welcome.instance_name

    # ---- plumbing --------------------------------------------------------------------------
    def close(self) -> None:
        local, self._local = self._local, None
        if local is not None:
            local.close()
        self._sock.close()

    def local(self) -> Local:
        """What the commands that run in this process use: this connection to ask the
        manager, its address for their libln clients, what they keep until close()."""
        if self._local is None:
            def control(op: str, **fields: Any) -> dict[str, Any]:
                try:
                    return self.command(op, **fields)
                except ManagerError as exc:
                    raise ControlError(str(exc)) from None

            self._local = Local(control, self.address, "ln_script")
        return self._local

    def __enter__(self) -> Manager:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _send(self, msg: p.Message) -> None:
        try:
            self._sock.sendall(p.encode(msg))
        except OSError as exc:
            raise ManagerError(f"connection to the manager lost: {exc}") from None

    def _receive(self, timeout: float | None) -> p.Message:
        self._sock.settimeout(timeout)
        try:
            return receive(self._sock, ManagerError)
        except TimeoutError:
            raise ManagerError("no answer from the manager in time") from None
        except OSError as exc:
            raise ManagerError(f"connection to the manager lost: {exc}") from None

    def control(self, op: str, **args: Any) -> dict[str, Any]:
        """Same as command(): the name the Python client uses, so both reach loggers."""
        return self.command(op, **args)

    def get_logger(self, name: str) -> Any:
        """The manager's topic logger `name` (made if missing): add_topic, enable,
        disable, status, download, save (docs/logging.md)."""
        from .._logger import logger

        return logger(self, name)

    def command(self, op: str, *, wait: float | None = None, **args: Any) -> dict[str, Any]:
        """Send one control command; its result dict.  `wait` is how long the command itself
        may take (None: forever) on top of the connection's timeout."""
        self._next_id += 1
        self._send(p.Control(self._next_id, json.dumps({"op": op, **args})))
        cmd = command_entry(op)
        # a command that runs in a client takes its own time there (the manager's worker)
        limit = None if wait is None and cmd is not None and (cmd.slow or cmd.run) \
            else (wait or 0) + self.timeout
        reply = self._receive(limit)
        if isinstance(reply, p.Error):
            raise ManagerError(reply.text)
        if not isinstance(reply, p.ControlResult) or reply.request_id != self._next_id:
            raise ManagerError(f"unexpected answer {reply.TYPE.name} to {op}")
        try:
            result = json.loads(reply.result)
        except ValueError as exc:
            raise ManagerError(f"malformed answer from the manager: {exc}") from None
        if not isinstance(result, dict):
            raise ManagerError("malformed answer from the manager: not a JSON object")
        if not result.get("ok"):
            raise ManagerError(str(result.get("error", "unknown error")))
        return result

    # ---- commands ------------------------------------------------------------------------
    # start, stop, restart, wait_ready, status, output, history, topics, services, hosts,
    # network, pull, reload, quit, detach, events, logger_*, ...: one method per command
    # of the table (commands/), added below the class by add_methods().
    def __getattr__(self, name: str) -> Any:
        """The method of a command registered after this module was imported."""
        if not name.startswith("_"):
            for cmd in commands():
                if cmd.script_name == name:
                    return method(cmd).__get__(self)
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    def state(self, name: str) -> str:
        """The state of process `name` ("ready", "stopped", ...)."""
        for entry in self.status():  # type: ignore[attr-defined]
            if entry["name"] == name:
                return str(entry["state"])
        raise ManagerError(f"no process named {name!r}")


add_methods(Manager)


def connect(address: str | None = None, *, timeout: float = DEFAULT_TIMEOUT) -> Manager:
    """A connection to the manager at `address` ("HOST:PORT", default $LN_MANAGER)."""
    address = address or os.environ.get("LN_MANAGER")
    if not address:
        raise ManagerError("no manager address: pass HOST:PORT or set LN_MANAGER")
    return Manager(address, timeout=timeout)
