"""Read and call operations the web UI needs beyond the manager's control commands: the
process tree (groups, dependencies), a topic's numeric fields, a service's request form and
a call of it, and the parameter blocks.  Registered into the manager's command table
(commands/) where a command of the same name is not there already."""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING, Any

from .fields import numeric_fields
from ..control import loop_control
from .worker import in_thread

if TYPE_CHECKING:
    from ..control import Control

def _command(name: str, help: str, handler: Any, args: tuple[Any, ...] = (),
             result: str = "{}", changes_state: bool = False) -> Any:
    from ..commands import Command

    return Command(name, help, "webui", handler, args, result=result,
                   changes_state=changes_state, console=False, cli=False, script="")


def register_ops() -> None:
    """Put the web UI's operations into the command table (those not there already)."""
    from ..commands import Arg, command, register

    name = Arg("name", "str", "the topic or service", required=True, nonempty=True)
    block = Arg("block", "str", "a parameter block (its id or a unique end of it)",
                required=True, nonempty=True)
    entries = [
        _command("process_tree", "groups, each process's dependencies and what it waits on",
                 process_tree, result="{groups: [{name, members}], processes: [{name, "
                                      "depends_on, waiting_on, ready_on, node}]}"),
        _command("topic_fields", "a topic's numeric fields, one path per number",
                 topic_fields, (name,), "{name, md_name, fields: [{path, type}]}"),
        _command("service_form", "a service's request and response fields", service_form,
                 (name,), "{name, md_name, request: [field], response: [field]}"),
        _command("service_call", "call a service with field values (or request text)",
                 service_call, (name, Arg("request", "json", "field values or request text",
                                          default={}),
                                Arg("timeout", "float", "seconds", default=10.0, low=0.001,
                                    high=300)),
                 "{response}", changes_state=True),
        _command("param_list", "the parameter blocks", param_list, (),
                 "{blocks: [{id, service, provider}]}"),
        _command("param_get", "a block's parameters with the loop's values", param_get,
                 (block,), "{id, parameters: [...]}"),
        _command("param_set", "override parameters of one block (all or none)", param_set,
                 (block, Arg("values", "json", "{parameter: value}", required=True)),
                 "{result}", changes_state=True),
    ]
    register(*[e for e in entries if command(e.name) is None])


def _error(text: str) -> Exception:
    from ..control import ControlError

    return ControlError(text)


def _string(command: dict[str, Any], key: str) -> str:
    value = command.get(key)
    if not isinstance(value, str) or not value:
        raise _error(f'"{key}" must be a non-empty string')
    return value


async def process_tree(control: Control, command: dict[str, Any]) -> dict[str, Any]:
    """Groups with their members, each process's dependencies and what it waits for to be
    ready, and which of its dependencies are not up yet."""
    sched = control.scheduler
    if sched is None:
        return {"groups": [], "processes": []}
    config = sched.config
    groups = [{"name": name, "members": list(g.members)} for name, g in config.groups.items()]
    status = {p["name"]: p for p in sched.status()}
    out = []
    for name, rt in sched.procs.items():
        cfg = rt.cfg
        deps = list(cfg.depends_on)
        waiting = [d for d in deps if status.get(d, {}).get("state") not in ("ready",
                                                                            "finished")]
        ready_on = {k: getattr(cfg, k) for k in ("ready_on_topic", "ready_on_service",
                                                  "ready_regex", "ready_time")
                    if getattr(cfg, k, None)}
        out.append({"name": name, "depends_on": deps, "waiting_on": waiting,
                    "ready_on": ready_on, "node": cfg.node})
    return {"groups": groups, "processes": out}


def _address(control: Control) -> str:
    address = getattr(control, "manager_address", None)
    if not address:
        raise _error("this manager has no address for its own clients")
    return str(address)


async def topic_fields(control: Control, command: dict[str, Any]) -> dict[str, Any]:
    from ...introspection.commands import CommandError, Context, topic_info, topic_layout

    name = _string(command, "name")
    loop = asyncio.get_running_loop()

    def work() -> dict[str, Any]:
        ctx = Context(loop_control(control, loop, CommandError), _address(control),
                      lambda _line: None)
        info = topic_info(ctx, name)
        md = topic_layout(info)
        return {"name": name, "md_name": md.name,
                "fields": [{"path": f.path, "type": f.type} for f in numeric_fields(md.struct)]}

    try:
        return await in_thread(work)  # type: ignore[no-any-return]
    except CommandError as exc:
        raise _error(str(exc)) from None


def _form(layout: Any) -> list[dict[str, Any]]:
    from ln_generate.model import Struct

    out: list[dict[str, Any]] = []
    for f in layout.fields:
        entry: dict[str, Any] = {"name": f.name, "kind": f.kind, "count": f.count,
                                 "doc": f.doc}
        if isinstance(f.type, Struct):
            entry["type"] = "struct"
            entry["fields"] = _form(f.type)
        else:
            entry["type"] = f.type.name
        out.append(entry)
    return out


async def service_form(control: Control, command: dict[str, Any]) -> dict[str, Any]:
    from ...introspection.values import IntrospectError
    from ...introspection.client import load_md

    name = _string(command, "name")
    info = await control.handle({"op": "service_info", "name": name})
    try:
        md = await in_thread(load_md, info["md_name"], info["md_dirs"])
    except IntrospectError as exc:
        raise _error(f"service {name!r}: {exc}") from None
    if md.kind != "service":
        raise _error(f"service {name!r}: md {md.name!r} is not a service")
    return {"name": name, "md_name": md.name, "request": _form(md.sections["request"]),
            "response": _form(md.sections["response"])}


async def service_call(control: Control, command: dict[str, Any]) -> dict[str, Any]:
    from ...introspection.values import jsonable
    from ...introspection.commands import CommandError, Context, service_call_values

    name = _string(command, "name")
    request = command.get("request", {})
    if not isinstance(request, dict | str):
        raise _error('"request" must be an object of field values or request text')
    timeout = command.get("timeout", 10.0)
    if isinstance(timeout, bool) or not isinstance(timeout, int | float) or not \
            0 < timeout <= 300:
        raise _error('"timeout" must be 0..300 seconds')
    loop = asyncio.get_running_loop()

    def work() -> dict[str, Any]:
        ctx = Context(loop_control(control, loop, CommandError), _address(control),
                      lambda _line: None, client_prefix="ln_webui")
        return service_call_values(ctx, name, request, float(timeout))

    try:
        return {"response": jsonable(await in_thread(work))}
    except CommandError as exc:
        raise _error(str(exc)) from None


async def _param(control: Control, func: Any) -> dict[str, Any]:
    from ...parameters.tools import ParamError, Session

    loop = asyncio.get_running_loop()

    def work() -> dict[str, Any]:
        with Session(loop_control(control, loop, ParamError), _address(control),
                     "ln_webui_param") as session:
            return func(session)  # type: ignore[no-any-return]

    try:
        return await in_thread(work)  # type: ignore[no-any-return]
    except ParamError as exc:
        raise _error(str(exc)) from None


async def param_list(control: Control, command: dict[str, Any]) -> dict[str, Any]:
    return await _param(control, lambda s: {"blocks": [
        {"id": b.id, "service": b.service, "provider": b.provider} for b in s.blocks()]})


async def param_get(control: Control, command: dict[str, Any]) -> dict[str, Any]:
    from ...parameters.tools import to_json

    block = _string(command, "block")

    def get(s: Any) -> dict[str, Any]:
        import json

        answer = s.describe(block)
        return json.loads(to_json(answer))  # type: ignore[no-any-return]
    return await _param(control, get)


async def param_set(control: Control, command: dict[str, Any]) -> dict[str, Any]:
    from ...parameters.tools import parse_value

    block = _string(command, "block")
    values = command.get("values")
    if not isinstance(values, dict) or not values:
        raise _error('"values" must be an object {parameter: value}')
    parsed = {k: parse_value(v) if isinstance(v, str) else v for k, v in values.items()}
    return await _param(control, lambda s: {"result": s.set(block, parsed)})
