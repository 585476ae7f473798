"""Read operations the web UI needs beyond the manager's other commands: the process tree
(groups, dependencies), a topic's numeric fields, a service's request form (it calls the
service with the table's `service_call`, the parameter blocks with `param_*`).  Registered
into the manager's command table (tools/commands/) where a command of the same name is not
there already."""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING, Any

from ....tools.commands.from_thread import loop_control
from .fields import numeric_fields
from .worker import in_thread

if TYPE_CHECKING:
    from ..control import Control

def _command(name: str, help: str, handler: Any, args: tuple[Any, ...] = (),
             result: str = "{}", changes_state: bool = False) -> Any:
    from ....tools.commands import Command

    return Command(name, help, "webui", handler, args, result=result,
                   changes_state=changes_state, console=False, cli=False, script="")


def register_ops() -> None:
    """Put the web UI's operations into the command table (those not there already)."""
    from ....tools.commands import Arg, command, register

    name = Arg("name", "str", "the topic or service", required=True, nonempty=True)
    entries = [
        _command("process_tree", "groups, each process's dependencies and what it waits on",
                 process_tree, result="{groups: [{name, members}], processes: [{name, "
                                      "depends_on, waiting_on, ready_on, node}]}"),
        _command("topic_fields", "a topic's numeric fields, one path per number",
                 topic_fields, (name,), "{name, md_name, fields: [{path, type}]}"),
        _command("service_form", "a service's request and response fields", service_form,
                 (name,), "{name, md_name, request: [field], response: [field]}"),
    ]
    register(*[e for e in entries if command(e.name) is None])


def _error(text: str) -> Exception:
    from ....tools.commands import ControlError

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
    from ....tools.introspection.commands import (
        CommandError,
        Context,
        topic_info,
        topic_layout,
    )

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
    from ....tools.introspection.client import load_md
    from ....tools.introspection.values import IntrospectError

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
