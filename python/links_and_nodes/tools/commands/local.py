"""Commands that run in a client of the manager (Command.run: `topic echo`, `param set`, ...):
what they are given (Local: how to ask the manager, where their libln clients connect, when
to stop, what they keep between commands) and their answer, the same for every front end."""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

from .arguments import check_args
from .spec import Command


@dataclass
class Local:
    """control(op, **fields) -> the manager's answer (ControlError when it refuses or cannot
    be reached); address: the manager's HOST:PORT for libln clients; client_prefix: the
    start of their names (`ln_console` -> `ln_console_topic_echo`); stop: set to end a
    command that streams."""

    control: Callable[..., dict[str, Any]]
    address: str
    client_prefix: str = "ln"
    stop: threading.Event = field(default_factory=threading.Event)
    kept: dict[str, Any] = field(default_factory=dict)

    def keep(self, key: str, make: Callable[[], Any]) -> Any:
        """What make() returns, made on the first call and kept until close() (the scripting
        client keeps one libln client for all its parameter commands)."""
        if key not in self.kept:
            self.kept[key] = make()
        return self.kept[key]

    def close(self) -> None:
        """Close what was kept (its close())."""
        kept, self.kept = self.kept, {}
        for thing in kept.values():
            thing.close()


def rows(cmd: Command, local: Local, args: dict[str, Any]) -> Iterator[dict[str, Any]]:
    """The rows of a command that runs here: what it streams, or its answer as the one row."""
    assert cmd.run is not None
    out = cmd.run(local, args)
    if cmd.streams:
        yield from out  # type: ignore[misc]
    else:
        yield out  # type: ignore[misc]


def answer(cmd: Command, local: Local, args: dict[str, Any]) -> dict[str, Any]:
    """The whole answer of a command that runs here: its result, or {"rows": [...]}."""
    got = list(rows(cmd, local, args))
    return {"rows": got} if cmd.streams else got[0]


def full_args(cmd: Command, request: dict[str, Any]) -> dict[str, Any]:
    """The arguments of a request checked (check_args; None: the default), with the defaults
    of the options of the console and the CLI only (a run reads them all)."""
    given = {k: v for k, v in request.items() if v is not None}
    return {**{a.name: a.default for a in cmd.args}, **check_args(cmd, given)}


def strict_json(value: Any) -> Any:
    """`value` for strict JSON (a browser's parser): NaN and the infinities as the strings
    "NaN", "Infinity", "-Infinity"."""
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    if isinstance(value, dict):
        return {k: strict_json(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [strict_json(v) for v in value]
    return value
