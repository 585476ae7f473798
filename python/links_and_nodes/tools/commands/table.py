"""The one table of manager commands.  The process commands (manager/frontends/commands/
process.py) and each feature module (introspection, events, loggers, pull topics,
parameters; the web UI's live subscriptions) put theirs in with one register(...) call;
Control.handle, the console, `ln_manager COMMAND` and the scripting API all read it from
here.  BUILTIN names the modules that register, as entry points do: they are imported on
the first look at the table, so importing this stays light (no libln, no manager)."""

from __future__ import annotations

import importlib
from typing import Any

from .spec import Command, Verb

# modules whose import registers commands, in the order their commands are listed
BUILTIN = ("links_and_nodes.manager.frontends.commands.process",
           "links_and_nodes.manager.frontends.commands.resource_view",
           "links_and_nodes.manager.frontends.commands.pull_view",
           "links_and_nodes.manager.introspection.control",
           "links_and_nodes.manager.introspection.graph",
           "links_and_nodes.manager.frontends.commands.event_control",
           "links_and_nodes.manager.frontends.commands.log_view",
           "links_and_nodes.manager.loggers.commands",
           "links_and_nodes.manager.parameters.commands")

_commands: dict[str, Command] = {}
_verbs: dict[str, Verb] = {}
_loading: list[bool] = []


def register(*entries: Command | Verb) -> None:
    """Add commands (and the first words of families, Verb) to the table; a name may be
    taken only once."""
    for entry in entries:
        into: dict[str, Any] = _commands if isinstance(entry, Command) else _verbs
        if not isinstance(entry, Command | Verb):
            raise TypeError(f"not a Command or Verb: {entry!r}")
        old = into.get(entry.name)
        if old is not None and old != entry:
            raise ValueError(f"command {entry.name!r} is in the table already")
        into[entry.name] = entry


def _load() -> None:
    if _loading:
        return
    _loading.append(True)
    for module in BUILTIN:
        importlib.import_module(module)


def commands() -> list[Command]:
    """Every command, in the order they were registered."""
    _load()
    return list(_commands.values())


def command(name: str) -> Command | None:
    _load()
    return _commands.get(name)


def verbs() -> list[Verb]:
    _load()
    return list(_verbs.values())


def verb(word: str) -> Verb | None:
    """The family that starts with `word`, if it has a Verb."""
    _load()
    return _verbs.get(word)


def console_entry(word: str) -> Command | None:
    """The command of its own (not of a family) that a console line starting with `word`
    runs."""
    _load()
    for cmd in _commands.values():
        if word and not cmd.phrase and (word == cmd.console_word or word in cmd.aliases):
            return cmd
    return None


def describe_arg(arg: Any) -> dict[str, Any]:
    entry = {"name": arg.name, "type": arg.type, "required": arg.required,
             "default": arg.default, "help": arg.help}
    if arg.choices:
        entry["choices"] = list(arg.choices)
    if arg.nullable:
        entry["nullable"] = True
    for key in ("low", "high"):
        if getattr(arg, key) is not None:
            entry[key] = getattr(arg, key)
    return entry


def describe() -> list[dict[str, Any]]:
    """Every command as JSON: name, help, group, args (name, type, required, default, help,
    choices, nullable, low, high), result, changes_state, session."""
    return [{"name": c.name, "help": c.help, "group": c.group,
             "args": [describe_arg(a) for a in c.args if a.at("")],
             "result": c.result, "changes_state": c.changes_state, "session": c.session}
            for c in commands()]
