"""ln_foxglove's connection to the manager: CONTROL commands (the scripting API's Manager)
shared by the discovery loop, the channel readers and the service handlers, one at a time.
A failed command drops the connection, and the next one connects again, so the bridge
outlives a manager restart."""

from __future__ import annotations

import threading
from typing import Any

from ..tools.introspection.commands import CommandError
from ..tools.scripting import Manager, ManagerError


class ManagerLink:
    def __init__(self, address: str, name: str) -> None:
        self.address = address
        self.name = name
        self._lock = threading.Lock()
        self._manager: Manager | None = Manager(address, name=name)  # ManagerError: at once
        self.instance = self._manager.instance

    def control(self, op: str, **args: Any) -> dict[str, Any]:
        """The manager's answer to one command; CommandError (one line) if it refused or
        could not be reached."""
        with self._lock:
            try:
                if self._manager is None:
                    self._manager = Manager(self.address, name=self.name)
                return self._manager.command(op, **args)
            except ManagerError as exc:
                if self._manager is not None:
                    self._manager.close()
                    self._manager = None
                raise CommandError(str(exc)) from None

    def close(self) -> None:
        with self._lock:
            if self._manager is not None:
                self._manager.close()
                self._manager = None
