"""Argument checks from the command table, the same for every front end: a JSON request
(CONTROL frame, WebSocket), the words of a console line and the CLI's argv all end in
check_value(), so a bad value gets the same text everywhere."""

from __future__ import annotations

import json
import math
import re
from typing import Any

from .spec import SAME, Arg, ArgError, Command

_INT = re.compile(r"[+-]?[0-9]+\Z")
_NOTHING: Any = object()  # error_text(): no value was given


def _range(arg: Arg, what: str) -> str:
    if arg.low is not None and arg.high is not None:
        return f"{what} from {arg.low:g} to {arg.high:g}" if arg.type == "float" else \
            f"{what} from {int(arg.low)} to {int(arg.high)}"
    if arg.low is not None:
        return f"{what} >= {arg.low:g}"
    if arg.high is not None:
        return f"{what} <= {arg.high:g}"
    return what


def error_text(arg: Arg, value: Any = _NOTHING) -> str:
    """What is wrong when the value of `arg` is missing or bad (`value`: as it was given,
    a word as typed, for an Arg.error that shows it)."""
    if arg.error and ("{value" not in arg.error or value is not _NOTHING):
        return arg.error.format(value=value) if "{value" in arg.error else arg.error
    name = f'"{arg.name}"'
    if arg.choices:
        text = f"{name} must be one of: {', '.join(str(c) for c in arg.choices)}"
    elif arg.type == "str":
        text = f"{name} must be a {'non-empty ' if arg.nonempty else ''}string"
    elif arg.type == "bool":
        text = f"{name} must be true or false"
    elif arg.type == "int":
        text = f"{name} must be {_range(arg, 'an integer')}"
    elif arg.type == "float":
        text = f"{name} must be {_range(arg, 'a finite number' if arg.finite else 'a number')}"
    else:
        text = f"{name} must be a JSON value"
    return text + (" or null" if arg.nullable else "")


def _fits(arg: Arg, value: Any) -> bool:
    t = arg.type
    if t == "str":
        return isinstance(value, str) and (bool(value) or not arg.nonempty)
    if t == "bool":
        return isinstance(value, bool)
    if t in ("int", "float"):
        if isinstance(value, bool) or not isinstance(value, int if t == "int" else int | float):
            return False
        if t == "float" and (arg.finite or arg.low is not None or arg.high is not None) \
                and not math.isfinite(value):
            return False
        return (arg.low is None or value >= arg.low) and (arg.high is None or value <= arg.high)
    return True


def check_value(arg: Arg, value: Any, code: str = "", given: Any = _NOTHING) -> Any:
    """`value` of `arg` from a JSON request (or converted from the word `given`), checked."""
    if value is None and arg.nullable:
        return None
    if not _fits(arg, value) or (arg.choices and value not in arg.choices):
        raise ArgError(error_text(arg, value if given is _NOTHING else given), code)
    return arg.check(value) if arg.check is not None else value


def check_args(cmd: Command, request: dict[str, Any]) -> dict[str, Any]:
    """Every argument of `cmd` (JSON front ends: where == "") from a request: checked values,
    defaults for those it leaves out.  Other keys of the request ("op", "id") are ignored."""
    args: dict[str, Any] = {}
    for arg in cmd.args:
        if not arg.at(""):
            continue
        if arg.name in request:
            args[arg.name] = check_value(arg, request[arg.name], cmd.code)
        elif arg.required:
            raise ArgError(error_text(arg), cmd.code)
        else:
            args[arg.name] = arg.default
    return args


def from_text(arg: Arg, text: str | list[str], code: str = "") -> Any:
    """A word typed for `arg` (the list of words of a rest="words" one), converted to its
    type and checked."""
    if isinstance(text, list):
        return check_value(arg, text, code, text)
    value: Any = text
    try:
        if arg.type == "int":
            if not _INT.match(text):
                raise ValueError(text)
            value = int(text)
        elif arg.type == "float":
            value = float(text)
        elif arg.type == "bool":
            value = {"true": True, "yes": True, "1": True, "false": False, "no": False,
                     "0": False}[text.lower()]
        elif arg.type == "json":
            try:
                value = json.loads(text)
            except ValueError:
                value = text  # a bare word is a string
    except (ValueError, KeyError):
        raise ArgError(error_text(arg, text), code) from None
    return check_value(arg, value, code, text)


def from_texts(cmd: Command, given: dict[str, Any], where: str) -> dict[str, Any]:
    """The arguments of `cmd` in front end `where` ("console" or "cli") from what was typed:
    {name: text, or True for a bool option given, or None for not given}."""
    args: dict[str, Any] = {}
    for arg in cmd.args:
        if not arg.at(where):
            continue
        text = given.get(arg.name)
        if text is None or (arg.type == "bool" and text is False):
            needed = arg.console_required if where == "console" else False
            if arg.positional and (needed or (arg.required and cmd.missing_usage)):
                raise ArgError(f"usage: {cmd.usage(where)}", cmd.code)
            if arg.required:
                raise ArgError(error_text(arg), cmd.code)
            args[arg.name] = arg.default if arg.text_default is SAME else arg.text_default
        elif text is True:
            args[arg.name] = True
        else:
            args[arg.name] = from_text(arg, text, cmd.code)
    return args


def is_number(word: str) -> bool:
    """Whether a console word is a number (so `-1` is a value, not an option)."""
    try:
        float(word)
    except ValueError:
        return False
    return True


def parse_words(cmd: Command, words: list[str], where: str = "console") -> dict[str, Any]:
    """The arguments of a console line (the words after the command), converted and
    checked; ArgError with a usage line for words that do not fit.  Once a rest argument's
    words begin, a word that is no option of the command is one of them (`-x` too)."""
    options = {spelling: a for a in cmd.args if not a.positional and a.at(where)
               for spelling in (a.option, a.short) if spelling}
    positionals = [a for a in cmd.args if a.positional and a.at(where)]
    rest = positionals[-1] if positionals and positionals[-1].rest else None
    given: dict[str, Any] = {}
    typed: list[Any] = []
    it = iter(words)
    for word in it:
        option, eq, inline = word.partition("=")
        arg = options.get(option) if word.startswith("-") and len(word) > 1 else None
        if arg is not None:
            if arg.type == "bool":
                if eq:
                    raise ArgError(f"{option} takes no value", cmd.code)
                given[arg.name] = True
                continue
            value = inline if eq else next(it, None)
            if value is None:
                raise ArgError(f"{option} needs a value", cmd.code)
            given[arg.name] = value
        elif word.startswith("-") and len(word) > 1 and not is_number(word) \
                and not (rest is not None and len(typed) >= len(positionals) - 1):
            raise ArgError(f"unknown option {word!r}", cmd.code)
        else:
            typed.append(word)
    if rest is not None and len(typed) >= len(positionals):
        keep = len(positionals) - 1
        left = typed[keep:]
        typed[keep:] = [left if rest.rest == "words" else " ".join(left)]
    if len(typed) > len(positionals):
        raise ArgError(f"usage: {cmd.usage(where)}", cmd.code)
    for arg, word in zip(positionals, typed, strict=False):
        given[arg.name] = word
    return from_texts(cmd, given, where)


def to_request(cmd: Command, args: dict[str, Any]) -> dict[str, Any]:
    """The JSON request for checked arguments: {"op": name, ...} without the options of
    one front end."""
    request: dict[str, Any] = {"op": cmd.name}
    for arg in cmd.args:
        if arg.at("") and arg.name in args \
                and (args[arg.name] is not None or arg.nullable):
            request[arg.name] = args[arg.name]
    return request
