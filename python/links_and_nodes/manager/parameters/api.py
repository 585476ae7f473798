"""Parameter blocks in the scripting API (docs/parameters.md): the param_* methods of
`links_and_nodes.manager.connect(...)`.  They call the blocks' services from one libln
client per connection (made on first use, closed with the connection); a block that refuses
raises ManagerError with its reason (`.kind` says what was wrong)."""

from __future__ import annotations

from pathlib import Path
from typing import Any


class Parameters:
    """Mixed into scripting.Manager, whose command() and address it uses."""

    address: str
    _param_session: Any = None

    def command(self, op: str, *, wait: float | None = None, **args: Any) -> dict[str, Any]:
        raise NotImplementedError

    def _params(self) -> Any:
        from .tools import ParamError, Session
        from ..frontends.scripting import ManagerError

        if self._param_session is None:
            def control(op: str, **fields: Any) -> dict[str, Any]:
                try:
                    return self.command(op, **fields)
                except ManagerError as exc:
                    raise ParamError(str(exc)) from None

            self._param_session = Session(control, self.address, "ln_script_param")
        return self._param_session

    def _param_call(self, func: Any, *args: Any) -> Any:
        from .tools import ParamError
        from ..frontends.scripting import ManagerError

        try:
            return func(*args)
        except ParamError as exc:
            error = ManagerError(str(exc))
            error.kind = exc.kind  # type: ignore[attr-defined]
            raise error from None

    def close_parameters(self) -> None:
        """Close the libln client of the param_* methods (close() does it)."""
        session, self._param_session = self._param_session, None
        if session is not None:
            session.close()

    def param_blocks(self) -> list[str]:
        """The ids ("<client>.<block>") of every parameter block."""
        return [b.id for b in self._param_call(self._params().blocks)]

    def param_list(self, block: str) -> dict[str, Any]:
        """The block's descriptors as its service lists them: {"id", "block", "client",
        "service", "generation", "updates", "config_errors", "parameters": [{"name", "type",
        "count", "description", "min", "max", "read_only", "has_input", "value", "input",
        "overridden", "override", "source", "generation", "pending"}, ...]} (values as of
        the loop's last report)."""
        return self._param_call(self._params().describe, block, None, False)

    def param_get(self, block: str, name: str | None = None,
                  wait: float | None = None) -> Any:
        """The value of parameter `name` as the loop has it now (its next update(), at most
        `wait` s, default 0.25), or {name: value} of every parameter of the block."""
        values = self._param_call(self._params().values, block, name, wait)
        return values[name] if name is not None else values

    def param_set(self, block: str, name: str | dict[str, Any], value: Any = None) -> int:
        """Override parameter `name` with `value`, or several at once with a dict {name:
        value} (all or none); visible at the loop's next update().  Returns the block's
        generation of the change."""
        values = name if isinstance(name, dict) else {name: value}
        return int(self._param_call(self._params().set, block, values)["generation"])

    def param_reset(self, block: str, name: str | list[str] | None = None) -> list[str]:
        """Remove the override of `name` (a list of them, or every one); returns the
        parameters that had one."""
        names = [name] if isinstance(name, str) else name
        return self._param_call(self._params().reset, block, names)["reset"]

    def param_changes(self, block: str, since: int = 0) -> list[dict[str, Any]]:
        """The block's remembered changes (its last 64) after generation `since`, oldest
        first: {"generation", "time" (s, CLOCK_REALTIME), "op" ("set", "config", "reset"),
        "parameters", "values" (a set's values, if small)}."""
        return self._param_call(self._params().changes, block, since)["changes"]

    def param_save(self, path: str | Path) -> dict[str, Any]:
        """Write every block's writable values to a JSON file here; {"path", "blocks",
        "parameters"}."""
        return self._param_call(self._params().save, Path(path))

    def param_load(self, path: str | Path) -> dict[str, Any]:
        """Set the values of a file written by param_save, one request per block; {"path",
        "loaded": [ids], "errors": [texts]} (blocks missing or refusing are only listed)."""
        return self._param_call(self._params().load, Path(path))
