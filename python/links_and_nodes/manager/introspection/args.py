"""The words of the live introspection commands (docs/introspection.md), the same in the
console and as `ln_manager topic|md|service ...`: one table of commands with their
positionals and options, and a parser that turns words into arguments or a one-line
usage error."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from ..frontends.commands.check import is_number
from .stats import DEFAULT_WINDOW

GROUPS = ("topic", "md", "service")
DEFAULT_TIMEOUT = 10.0  # seconds a service call may take


class UsageError(Exception):
    """Words that are no valid command: one line (the caller adds the usage)."""


def _count(text: str) -> int:
    if not (text.isascii() and text.isdigit()) or int(text) < 1:
        raise ValueError("a whole number of at least 1")
    return int(text)


def _window(text: str) -> int:
    if not (text.isascii() and text.isdigit()) or int(text) < 2:
        raise ValueError("a whole number of at least 2")
    return int(text)


def _seconds(text: str) -> float:
    value = float(text)
    if not 0 < value < 1e9:  # also refuses NaN
        raise ValueError("a number of seconds above 0")
    return value


@dataclass(frozen=True)
class Spec:
    usage: str
    text: str
    positionals: tuple[str, ...]
    # option -> (name, converter); a converter of None makes a flag (True when given)
    options: dict[str, tuple[str, Callable[[str], Any] | None]] = field(default_factory=dict)
    rest: bool = False  # the last positional takes every remaining word, joined by spaces


_WATCH = {"-n": ("n", _count), "--duration": ("duration", _seconds)}
SPECS: dict[tuple[str, str], Spec] = {
    ("topic", "echo"): Spec(
        "topic echo NAME [-n N] [--duration S] [--field F] [--json] [--full]",
        "print samples decoded by the topic's md (-n: stop after N)", ("name",),
        {**_WATCH, "--field": ("field", str), "--json": ("json", None),
         "--full": ("full", None)}),
    ("topic", "hz"): Spec(
        "topic hz NAME [--window N] [-n N] [--duration S]",
        "rate and period statistics from the publish timestamps, every second", ("name",),
        {**_WATCH, "--window": ("window", _window)}),
    ("topic", "bw"): Spec(
        "topic bw NAME [--window N] [-n N] [--duration S]",
        "bytes per second (message size x rate), every second", ("name",),
        {**_WATCH, "--window": ("window", _window)}),
    ("topic", "info"): Spec(
        "topic info NAME [--json]",
        "md, layout, ring, publishers and subscribers with clients, hosts, transports",
        ("name",), {"--json": ("json", None)}),
    ("md", "show"): Spec(
        "md show NAME [--recursive]",
        "the text of a message definition (with -r also of the mds it uses)", ("name",),
        {"--recursive": ("recursive", None), "-r": ("recursive", None)}),
    ("service", "call"): Spec(
        "service call NAME [REQUEST] [--json] [--full] [--timeout S]",
        "call a service with REQUEST fields ('a: 1, b: [1, 2], name: \"x\"' or JSON)",
        ("name", "request"),
        {"--json": ("json", None), "--full": ("full", None), "--timeout": ("timeout", _seconds)},
        rest=True),
}
DEFAULTS: dict[str, Any] = {"n": None, "duration": None, "field": None, "json": False,
                            "full": False, "window": DEFAULT_WINDOW, "recursive": False,
                            "timeout": DEFAULT_TIMEOUT, "request": ""}


def usage(group: str | None = None) -> list[str]:
    """The usage lines of every command (of one group)."""
    return [line for key, s in SPECS.items() if group is None or key[0] == group
            for line in (f"  {s.usage}", f"      {s.text}")]


def parse(words: list[str]) -> tuple[tuple[str, str], dict[str, Any]]:
    """(group, command) and the arguments of `words` (group first); UsageError."""
    if len(words) < 2 or (words[0], words[1]) not in SPECS:
        group = words[0] if words else ""
        known = sorted(c for g, c in SPECS if g == group)
        if not known:
            raise UsageError(f"unknown command {group!r}")
        got = f"unknown {group} command {words[1]!r}" if len(words) > 1 else \
            f"{group} needs a command"
        raise UsageError(f"{got} (one of: {', '.join(known)})")
    key = (words[0], words[1])
    spec = SPECS[key]
    args: dict[str, Any] = {name: DEFAULTS[name] for name, _ in spec.options.values()}
    positionals: list[str] = []
    it = iter(words[2:])
    for word in it:
        option, eq, inline = word.partition("=")
        if word.startswith("-") and len(word) > 1 and option in spec.options:
            name, convert = spec.options[option]
            if convert is None:
                if eq:
                    raise UsageError(f"{option} takes no value")
                args[name] = True
                continue
            value = inline if eq else next(it, None)
            if value is None:
                raise UsageError(f"{option} needs a value")
            try:
                args[name] = convert(value)
            except ValueError as exc:
                what = str(exc) if str(exc).startswith("a ") else "a number"
                raise UsageError(f"{option}: {value!r} is not {what}") from None
        elif word.startswith("-") and len(word) > 1 and not is_number(word) \
                and not (spec.rest and len(positionals) >= len(spec.positionals) - 1):
            raise UsageError(f"unknown option {word!r}")
        else:
            positionals.append(word)
    if spec.rest and len(positionals) > len(spec.positionals):
        keep = len(spec.positionals) - 1
        positionals[keep:] = [" ".join(positionals[keep:])]
    if not positionals or len(positionals) > len(spec.positionals) \
            or (len(positionals) < len(spec.positionals) and not spec.rest):
        raise UsageError(f"usage: {spec.usage}")
    for index, name in enumerate(spec.positionals):
        args[name] = positionals[index] if index < len(positionals) else DEFAULTS[name]
    return key, args


