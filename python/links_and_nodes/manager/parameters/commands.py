"""The words of `param ...` in the console and of `ln_manager param ...` (docs/parameters.md):
parsed here and carried out on a param_tools.Session, their output as lines of text or, with
--json, one JSON document.  ParamUsage for words that make no command, ParamError for a
command that fails."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..frontends.commands import Verb, register
from .tools import (
    ParamError,
    Session,
    change_text,
    parse_value,
    range_text,
    state_text,
    type_text,
    value_text,
)

USAGE = """param list [BLOCK]                     blocks, or the parameters of one block
param get BLOCK [PARAM] [--wait S]     values as the loop has them now
param set BLOCK PARAM VALUE [PARAM VALUE ...]
                                       override (several: all at once or none)
param reset BLOCK [PARAM ...]          back to the program's own value
param changes BLOCK [--since G] [--follow]
                                       the block's last changes (--follow: ln_manager only)
param save FILE | param load FILE      every block's values to / from a JSON file
(--json: the answer as JSON; VALUE: JSON or 1.5, [1, 2], "text", nan)"""


FOLLOW_PERIOD = 0.2  # s between looks of `param changes --follow`


class ParamUsage(Exception):
    """Words that are no param command."""


def _options(words: list[str]) -> tuple[list[str], bool, float | None]:
    rest: list[str] = []
    as_json, wait = False, None
    it = iter(words)
    for word in it:
        if word == "--json":
            as_json = True
        elif word in ("--since", "--follow"):  # param changes reads them
            rest.append(word)
            if word == "--since":
                rest.append(next(it, ""))
        elif word == "--wait":
            text = next(it, None)
            try:
                wait = float(text) if text is not None else None
            except ValueError:
                wait = None
            if wait is None or not 0 <= wait <= 10:
                raise ParamUsage("--wait needs a number of seconds 0..10")
        else:
            rest.append(word)
    return rest, as_json, wait


def _json(say: Callable[[str], None], value: Any) -> None:
    for line in json.dumps(value, indent=2, ensure_ascii=False).splitlines():
        say(line)


def _table(rows: list[list[str]]) -> list[str]:
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    return ["  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip()
            for row in rows]


def _list(s: Session, args: list[str], say: Callable[[str], None], as_json: bool) -> None:
    if len(args) > 1:
        raise ParamUsage("usage: param list [BLOCK]")
    if args:
        answer = s.describe(args[0])
        if as_json:
            _json(say, answer)
            return
        rows = [["parameter", "type", "value", "override", "range", "description"]]
        for p in answer["parameters"]:
            rows.append([p["name"], type_text(p), value_text(p, p["value"]), state_text(p),
                         range_text(p), p["description"]])
        for line in _table(rows):
            say(line)
        for text in answer.get("config_errors", []):
            say(f"configuration refused: {text}")
        return
    found = []
    for block in s.blocks():
        answer = s.query(block, "list")
        found.append({"block": block.id, "service": block.service, "client": block.provider,
                      "parameters": len(answer["parameters"]),
                      "overridden": sum(p["overridden"] for p in answer["parameters"]),
                      "updates": answer["updates"]})
    if as_json:
        _json(say, found)
        return
    rows = [["block", "service", "parameters", "overridden", "updates"]]
    rows += [[f["block"], f["service"], str(f["parameters"]), str(f["overridden"]),
              str(f["updates"])] for f in found]
    for line in _table(rows):
        say(line)


def _get(s: Session, args: list[str], say: Callable[[str], None], as_json: bool,
         wait: float | None) -> None:
    if len(args) not in (1, 2):
        raise ParamUsage("usage: param get BLOCK [PARAM] [--wait S]")
    answer = s.describe(args[0], args[1] if len(args) > 1 else None, wait=wait)
    if as_json:
        _json(say, answer)
        return
    params = answer["parameters"]
    if len(args) == 2:
        say(value_text(params[0], params[0]["value"]))
        return
    for p in params:
        line = f"{p['name']}: {value_text(p, p['value'])}"
        if p["overridden"]:
            line += f"  (overridden by {p['source']}"
            line += ", pending)" if p["pending"] else ")"
        say(line)
    if not answer["live"]:
        say(f"(the loop has not updated within the wait: values as of its update "
            f"{answer['values_update']})")


def _set(s: Session, args: list[str], say: Callable[[str], None], as_json: bool) -> None:
    if len(args) < 3 or len(args) % 2 != 1:
        raise ParamUsage("usage: param set BLOCK PARAM VALUE [PARAM VALUE ...]")
    values: dict[str, Any] = {}
    for name, text in zip(args[1::2], args[2::2], strict=True):
        if name in values:
            raise ParamUsage(f"parameter {name!r} is given twice")
        values[name] = parse_value(text)
    answer = s.set(args[0], values)
    if as_json:
        _json(say, answer)
        return
    say(f"{answer['id']}: set {', '.join(answer['set'])} (generation {answer['generation']}; "
        "in effect at the loop's next update)")


def _reset(s: Session, args: list[str], say: Callable[[str], None], as_json: bool) -> None:
    if not args:
        raise ParamUsage("usage: param reset BLOCK [PARAM ...]")
    answer = s.reset(args[0], args[1:])
    if as_json:
        _json(say, answer)
        return
    say(f"{answer['id']}: reset {', '.join(answer['reset']) or 'nothing (no override)'}")


def _changes(s: Session, args: list[str], say: Callable[[str], None], as_json: bool,
             can_follow: bool, stop: Callable[[], bool]) -> None:
    usage = "usage: param changes BLOCK [--since GENERATION] [--follow]"
    since, follow, rest = 0, False, []
    it = iter(args)
    for word in it:
        if word == "--since":
            text = next(it, "")
            if not (text.isascii() and text.isdigit()):
                raise ParamUsage(usage)
            since = int(text)
        elif word == "--follow":
            follow = True
        else:
            rest.append(word)
    if len(rest) != 1:
        raise ParamUsage(usage)
    if follow and not can_follow:
        raise ParamUsage("--follow is for `ln_manager param changes`")
    while True:
        answer = s.changes(rest[0], since)
        if answer["changes"] and since and answer["changes"][0]["generation"] > since + 1:
            say(f"({answer['changes'][0]['generation'] - since - 1} older changes are "
                "no longer remembered)")
        for change in answer["changes"]:
            say(json.dumps(change, ensure_ascii=False) if as_json else change_text(change))
        since = answer["generation"]
        if not follow or stop():
            return
        time.sleep(FOLLOW_PERIOD)


def _file(s: Session, op: str, args: list[str], say: Callable[[str], None],
          as_json: bool) -> None:
    if len(args) != 1:
        raise ParamUsage(f"usage: param {op} FILE")
    path = Path(args[0]).expanduser()
    answer = s.save(path) if op == "save" else s.load(path)
    if as_json:
        _json(say, answer)
    elif op == "save":
        say(f"saved {answer['parameters']} parameters of {answer['blocks']} blocks to "
            f"{answer['path']}")
    else:
        say(f"loaded {len(answer['loaded'])} blocks from {answer['path']}"
            + (f": {', '.join(answer['loaded'])}" if answer["loaded"] else ""))
    if op == "load" and answer["errors"]:
        raise ParamError("; ".join(answer["errors"]))


def run(s: Session, words: list[str], say: Callable[[str], None], can_follow: bool = False,
        stop: Callable[[], bool] = lambda: False) -> None:
    """Carry out `param WORDS...` (without the leading "param"); `param changes --follow`
    (only with can_follow) polls until stop() or Ctrl-C."""
    args, as_json, wait = _options(words)
    if not args:
        raise ParamUsage(USAGE)
    op, rest = args[0], args[1:]
    if wait is not None and op != "get":
        raise ParamUsage("--wait is for param get")
    if op == "list":
        _list(s, rest, say, as_json)
    elif op == "get":
        _get(s, rest, say, as_json, wait)
    elif op == "set":
        _set(s, rest, say, as_json)
    elif op == "reset":
        _reset(s, rest, say, as_json)
    elif op == "changes":
        _changes(s, rest, say, as_json, can_follow, stop)
    elif op in ("save", "load"):
        _file(s, op, rest, say, as_json)
    else:
        raise ParamUsage(f"unknown param command {op!r}\n{USAGE}")


# ---- the table -------------------------------------------------------------------------------
async def _console(console: Any, words: list[str]) -> None:
    from .console import execute

    await execute(console, words)


def _cli(argv: list[str]) -> int:
    from .cli import main

    return main(argv)


register(Verb("param", "parameter blocks of the processes (docs/parameters.md)", "parameters",
              tuple(USAGE.splitlines()), _console, _cli,
              ("list", "get", "set", "reset", "changes", "save", "load")))
