"""The parameter tools (docs/parameters.md): find the parameter blocks of a running system
and list, get, set, reset, save and load their values, for the `param ...` commands
(commands.py) in every front end.  A block is a service with md ln/parameters/query named
"<client>.parameters.<block>"; the tools know it as "<client>.<block>" and call its service
from an ordinary libln client.  Every failure is a ParamError of one line."""

from __future__ import annotations

import json
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .values import ParamError, to_json

MD = "ln/parameters/query"
INFIX = ".parameters."
FILE_FORMAT = "ln_parameters/1"
CALL_TIMEOUT = 15.0  # s for one call of a block's service (a get waits up to 10 s itself)
_SPECIAL = {"NaN": math.nan, "Infinity": math.inf, "-Infinity": -math.inf}


@dataclass(frozen=True)
class Block:
    id: str       # "<client>.<block>"
    service: str  # "<client>.parameters.<block>"
    provider: str


def block_id(service: str) -> str:
    head, _, tail = service.rpartition(INFIX)
    return f"{head}.{tail}"


def blocks(control: Callable[..., dict[str, Any]]) -> list[Block]:
    """Every parameter block the manager has a service of, by id."""
    found = [Block(block_id(s["name"]), s["name"], s.get("provider", ""))
             for s in control("services")["services"]
             if s.get("md_name") == MD and INFIX in s["name"]]
    return sorted(found, key=lambda b: b.id)


def resolve(found: list[Block], name: str) -> Block:
    """The block `name` names: its id or service name, or a unique ending of its id at a
    '.' ("gains" for "arm.controller.gains")."""
    for b in found:
        if name in (b.id, b.service):
            return b
    matches = [b for b in found if b.id.endswith("." + name)]
    if len(matches) == 1:
        return matches[0]
    known = ", ".join(b.id for b in found) or "none"
    if matches:
        raise ParamError(f"parameter block {name!r} is ambiguous: "
                         f"{', '.join(b.id for b in matches)}")
    raise ParamError(f"no parameter block {name!r} (blocks: {known})")


def pythonize(param: dict[str, Any], value: Any) -> Any:
    """A value of `param` (a descriptor from list/get) with "NaN"/"Infinity" of a float
    parameter as floats."""
    if param.get("type") not in ("float", "double"):
        return value
    if isinstance(value, list):
        return [_SPECIAL.get(v, v) if isinstance(v, str) else v for v in value]
    return _SPECIAL.get(value, value) if isinstance(value, str) else value


class Session:
    """A libln client that calls block services (one call at a time; thread-safe).
    control(op, **fields) asks the manager (CONTROL commands)."""

    def __init__(self, control: Callable[..., dict[str, Any]], address: str,
                 client_name: str = "ln_param") -> None:
        self.control = control
        self.address = address
        self.client_name = client_name
        self._client: Any = None
        self._services: dict[str, Any] = {}
        self._lock = threading.Lock()

    def close(self) -> None:
        with self._lock:
            client, self._client = self._client, None
            self._services.clear()
            if client is not None:
                client.close()

    def __enter__(self) -> Session:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def blocks(self) -> list[Block]:
        return blocks(self.control)

    def block(self, name: str) -> Block:
        return resolve(self.blocks(), name)

    def query(self, block: Block, op: str, name: str = "", value: str = "") -> dict[str, Any]:
        """One call of the block's service: its result (a dict); ParamError when the block
        refuses (with its reason) or the call fails."""
        from ...errors import LnError

        with self._lock:
            try:
                if self._client is None:
                    from ..._client import client

                    if not self.address:
                        raise ParamError("no address of the manager for a client to "
                                         "connect to")
                    self._client = client(self.client_name, self.address, reconnect=False)
                svc = self._services.get(block.service)
                if svc is None:
                    svc = self._client.get_service(block.service, MD)
                    self._services[block.service] = svc
                svc.req.op = op
                svc.req.name = name
                svc.req.value = value
                resp = svc.call(timeout=CALL_TIMEOUT)
                status, kind, reason = resp.status, resp.error, resp.reason
                result = resp.result
            except LnError as exc:
                self._services.pop(block.service, None)
                raise ParamError(f"{block.id}: the call of {block.service} failed: "
                                 f"{exc}") from None
        if status != 0:
            raise ParamError(f"{block.id}: {reason} ({kind})", kind)
        try:
            answer: dict[str, Any] = json.loads(result) if result else {}
        except ValueError as exc:
            raise ParamError(f"{block.id}: malformed answer: {exc}") from None
        return answer

    # ---- the commands ----------------------------------------------------------------------
    def describe(self, name: str, param: str | None = None, live: bool = True,
                 wait: float | None = None) -> dict[str, Any]:
        """The block's list (live: get, with the loop's current values) as its service
        answers it, with "id" added."""
        block = self.block(name)
        value = "" if wait is None else json.dumps({"wait": wait})
        answer = self.query(block, "get" if live else "list", param or "", value)
        answer["id"] = block.id
        return answer

    def values(self, name: str, param: str | None = None,
               wait: float | None = None) -> dict[str, Any]:
        """{parameter: value} of the block (only `param` if given), as the loop has them."""
        answer = self.describe(name, param, wait=wait)
        return {p["name"]: pythonize(p, p["value"]) for p in answer["parameters"]}

    def set(self, name: str, values: dict[str, Any]) -> dict[str, Any]:
        """Override several parameters of one block at once (all or nothing); values as
        Python values (or text already parsed)."""
        block = self.block(name)
        if len(values) == 1:
            ((param, value),) = values.items()
            answer = self.query(block, "set", param, to_json(value))
        else:
            text = "{" + ", ".join(f"{json.dumps(k)}: {to_json(v)}"
                                   for k, v in values.items()) + "}"
            answer = self.query(block, "set", "", text)
        answer["id"] = block.id
        return answer

    def reset(self, name: str, params: list[str] | None = None) -> dict[str, Any]:
        """Remove the overrides of `params` (every one if None or empty), as one change."""
        block = self.block(name)
        answer = self.query(block, "reset", "", json.dumps(params) if params else "")
        return {"id": block.id, "generation": answer["generation"], "reset": answer["reset"]}

    def changes(self, name: str, since: int = 0) -> dict[str, Any]:
        """The block's remembered changes after generation `since` (the last 64 at most):
        {"id", "generation", "oldest", "changes": [{"generation", "time", "op" ("set",
        "config", "reset"), "parameters", "values" (a set's new values, if small)}]}."""
        block = self.block(name)
        answer = self.query(block, "changes", "", json.dumps({"since": since}) if since else "")
        answer["id"] = block.id
        return answer

    def snapshot(self) -> dict[str, Any]:
        """Every block's settings now, in the format `save` writes: the value of every
        writable parameter without input, and of every overridden one (a parameter with
        input that is not overridden carries the program's own live value: pinning it on
        load would change what it is)."""
        saved: dict[str, dict[str, Any]] = {}
        for block in self.blocks():
            answer = self.query(block, "get")
            saved[block.id] = {p["name"]: p["override"] if p["overridden"] else p["value"]
                               for p in answer["parameters"]
                               if not p["read_only"] and (p["overridden"]
                                                          or not p["has_input"])}
        return {"format": FILE_FORMAT, "saved": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
                "blocks": saved}

    def save(self, path: Path) -> dict[str, Any]:
        data = self.snapshot()
        text = json.dumps(data, indent=2, ensure_ascii=False) + "\n"
        try:
            path.write_text(text, encoding="utf-8")
        except OSError as exc:
            raise ParamError(f"cannot write {path}: {exc.strerror or exc}") from None
        count = sum(len(v) for v in data["blocks"].values())
        return {"path": str(path), "blocks": len(data["blocks"]), "parameters": count}

    def load(self, path: Path) -> dict[str, Any]:
        """Set every value of a saved file, one request per block (all of a block or none
        of it).  Blocks that are not there or refuse are reported in "errors"; the others
        are set all the same."""
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except OSError as exc:
            raise ParamError(f"cannot read {path}: {exc.strerror or exc}") from None
        except ValueError as exc:
            raise ParamError(f"{path}: not JSON: {exc}") from None
        if not isinstance(data, dict) or data.get("format") != FILE_FORMAT \
                or not isinstance(data.get("blocks"), dict):
            raise ParamError(f"{path}: not a parameter file (format {FILE_FORMAT!r} with "
                             "\"blocks\")")
        found = self.blocks()
        loaded: list[str] = []
        errors: list[str] = []
        for name, values in data["blocks"].items():
            match = [b for b in found if b.id == name]
            if not match:
                errors.append(f"no parameter block {name!r}")
                continue
            if not isinstance(values, dict) or not values:
                continue
            text = "{" + ", ".join(f"{json.dumps(k)}: {json.dumps(v)}"
                                   for k, v in values.items()) + "}"
            try:
                self.query(match[0], "set", "", text)
                loaded.append(name)
            except ParamError as exc:
                errors.append(str(exc))
        return {"path": str(path), "loaded": loaded, "errors": errors}


# ---- text ------------------------------------------------------------------------------------
def type_text(p: dict[str, Any]) -> str:
    return p["type"] if p["count"] == 1 else f"{p['type']}[{p['count']}]"


def range_text(p: dict[str, Any]) -> str:
    if p["min"] is None and p["max"] is None:
        return "-"
    low = "-inf" if p["min"] is None else _number(p["min"])
    high = "inf" if p["max"] is None else _number(p["max"])
    return f"[{low}, {high}]"


def _number(v: Any) -> str:
    return str(int(v)) if isinstance(v, float) and v.is_integer() else str(v)


def value_text(p: dict[str, Any], value: Any) -> str:
    from ..introspection.values import format_value

    return format_value(pythonize(p, value), full=True)


def change_text(change: dict[str, Any]) -> str:
    """One line of `param changes`: generation, local time, op and what changed."""
    stamp = time.strftime("%H:%M:%S", time.localtime(change["time"]))
    stamp += f".{int(change['time'] % 1 * 1000):03d}"
    from ..introspection.values import format_value

    if "values" in change:
        what = ", ".join(f"{k} = {format_value(v)}" for k, v in change["values"].items())
    else:
        what = ", ".join(change["parameters"])
    return f"{change['generation']:>6}  {stamp}  {change['op']:<6}  {what}"


def state_text(p: dict[str, Any]) -> str:
    if p["read_only"]:
        return "read-only"
    if not p["overridden"]:
        return "-"
    return f"{p['source']}" + (" (pending)" if p["pending"] else "")
