"""The scripting API's command methods (links_and_nodes.manager.connect(...).start(...)),
made from the command table: one method per command, its signature and docstring from the
Args (or the command's script_args), its return value from the command's script_result.
A command that runs in the client (Command.run) runs in the script's process, its rows
collected.  A method the class defines itself (scripting.Manager.state) stays as it is."""

from __future__ import annotations

import inspect
import textwrap
from collections.abc import Callable
from typing import Any

from .errors import ControlError, ManagerError
from .local import full_args, rows
from .spec import ArgError, Command
from .table import commands

_TYPES: dict[str, Any] = {"str": str, "int": int, "float": float, "bool": bool, "json": Any}
P = inspect.Parameter


def signature(cmd: Command) -> inspect.Signature:
    """self, the positional arguments, then the others; bool options keyword-only, as is
    every argument after an optional one that has no default itself (or script_args's)."""
    params = [P("self", P.POSITIONAL_OR_KEYWORD)]
    if cmd.script_args is not None:
        own = inspect.signature(cmd.script_args)
        return own.replace(parameters=params + list(own.parameters.values()),
                           return_annotation=inspect.Signature.empty)
    keyword: list[inspect.Parameter] = []
    optional = False
    for arg in cmd.args:
        if not arg.at(""):
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
    named = set(inspect.signature(cmd.script_args).parameters) if cmd.script_args else None
    args = [a for a in cmd.args if a.at("") and (named is None or a.name in named)]
    if args:
        lines += ["", "Arguments:"]
        lines += [f"    {a.name} ({a.type}{', optional' if not a.required else ''}): {a.help}"
                  for a in args]
    lines += ["", *textwrap.wrap(f"The manager's answer: {cmd.result}", 88), "",
              f'(the "{cmd.name}" command, docs/process_management.md)']
    return "\n".join(lines)


def run_here(cmd: Command, local: Any, values: dict[str, Any]) -> Any:
    """A command that runs in the script's process: its answer (a streaming one's rows as a
    list); its refusals as ManagerError (with the `kind` of a refused parameter)."""
    try:
        args = full_args(cmd, values)
        got = list(rows(cmd, local, args))
    except (ArgError, ControlError) as exc:
        error = ManagerError(str(exc))
        error.kind = getattr(exc, "kind", "")  # type: ignore[attr-defined]
        raise error from None
    return got if cmd.streams else got[0]


def method(cmd: Command) -> Callable[..., Any]:
    sig = signature(cmd)

    def call(self: Any, *args: Any, **kwargs: Any) -> Any:
        bound = sig.bind(self, *args, **kwargs)
        bound.apply_defaults()
        values = dict(bound.arguments)
        del values["self"]
        if cmd.script_args is not None:
            values = cmd.script_args(**values)
        if cmd.run is not None:
            result = run_here(cmd, self.local(), values)
            return cmd.script_result(result) if cmd.script_result is not None else result
        wait = values.get(cmd.script_wait) if cmd.script_wait else None
        result = self.command(cmd.name, wait=wait, **values)
        if cmd.script_result is not None:
            return cmd.script_result(result)
        return {k: v for k, v in result.items() if k != "ok"}

    call.__name__ = call.__qualname__ = cmd.script_name
    call.__module__ = "links_and_nodes.tools.scripting"
    call.__doc__ = docstring(cmd)
    call.__signature__ = sig  # type: ignore[attr-defined]
    return call


def add_methods(cls: type) -> None:
    """A method on `cls` for every command of the table that has none there yet."""
    for cmd in commands():
        name = cmd.script_name
        if name and not hasattr(cls, name):
            setattr(cls, name, method(cmd))
