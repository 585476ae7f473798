"""The scripting API's command methods (links_and_nodes.manager.connect(...).start(...)),
made from the command table: one method per command, its signature and docstring from the
Args, its return value from the command's script_result.  A method the class defines
itself (scripting.Manager.state, introspect_api's md_show) stays as it is."""

from __future__ import annotations

import inspect
import textwrap
from collections.abc import Callable
from typing import Any

from .spec import Command
from .table import commands

_TYPES: dict[str, Any] = {"str": str, "int": int, "float": float, "bool": bool, "json": Any}
P = inspect.Parameter


def signature(cmd: Command) -> inspect.Signature:
    """self, the positional arguments, then the others; bool options keyword-only, as is
    every argument after an optional one that has no default itself."""
    params = [P("self", P.POSITIONAL_OR_KEYWORD)]
    keyword: list[inspect.Parameter] = []
    optional = False
    for arg in cmd.args:
        if arg.where:
            continue
        kind = P.KEYWORD_ONLY if arg.type == "bool" or (arg.required and optional) \
            else P.POSITIONAL_OR_KEYWORD
        annotation = _TYPES[arg.type]
        if arg.nullable:
            annotation = annotation | None if annotation is not Any else Any
        param = P(arg.name, kind, default=P.empty if arg.required else arg.default,
                  annotation=annotation)
        if kind is P.KEYWORD_ONLY:
            keyword.append(param)
        else:
            params.append(param)
            optional = optional or not arg.required
    return inspect.Signature(params + keyword)


def docstring(cmd: Command) -> str:
    lines = textwrap.wrap(cmd.script_doc or cmd.help[:1].upper() + cmd.help[1:] + ".", 88)
    args = [a for a in cmd.args if not a.where]
    if args:
        lines += ["", "Arguments:"]
        lines += [f"    {a.name} ({a.type}{', optional' if not a.required else ''}): {a.help}"
                  for a in args]
    lines += ["", *textwrap.wrap(f"The manager's answer: {cmd.result}", 88), "",
              f'(the "{cmd.name}" command, docs/process_management.md)']
    return "\n".join(lines)


def method(cmd: Command) -> Callable[..., Any]:
    sig = signature(cmd)

    def call(self: Any, *args: Any, **kwargs: Any) -> Any:
        bound = sig.bind(self, *args, **kwargs)
        bound.apply_defaults()
        values = dict(bound.arguments)
        del values["self"]
        wait = values.get(cmd.script_wait) if cmd.script_wait else None
        result = self.command(cmd.name, wait=wait, **values)
        if cmd.script_result is not None:
            return cmd.script_result(result)
        return {k: v for k, v in result.items() if k != "ok"}

    call.__name__ = call.__qualname__ = cmd.script_name
    call.__module__ = "links_and_nodes.manager.frontends.scripting"
    call.__doc__ = docstring(cmd)
    call.__signature__ = sig  # type: ignore[attr-defined]
    return call


def add_methods(cls: type) -> None:
    """A method on `cls` for every command of the table that has none there yet."""
    for cmd in commands():
        name = cmd.script_name
        if name and not hasattr(cls, name):
            setattr(cls, name, method(cmd))
