"""The `param ...` commands (docs/parameters.md) as they run in a client of the manager: each
takes a tools/commands Local (its Session, one libln client, kept there) and the checked
arguments, and returns the answer; `param changes` yields the changes as they come.  Their
text for the console and `ln_manager param` (--json: the answer as JSON) is here too."""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from ..commands import ArgError
from ..commands.columns import table
from .blocks import (
    Session,
    change_text,
    pythonize,
    range_text,
    state_text,
    type_text,
    value_text,
)
from .values import parse_value

# a console format of a command: its answer and arguments -> output lines
LineFormat = Callable[[dict[str, Any], dict[str, Any]], list[str]]

FOLLOW_PERIOD = 0.2  # s between looks of `param changes --follow`


def session(local: Any) -> Session:
    """The Session of `local`: one libln client calling the blocks, kept with it."""
    return local.keep("parameters", lambda: Session(
        local.control, local.address, f"{local.client_prefix}_param"))  # type: ignore[no-any-return]


# ---- the argument checks -----------------------------------------------------------------
def pairs(value: Any) -> dict[str, Any]:
    """`PARAM VALUE [PARAM VALUE ...]` as typed (a list of words), or {parameter: value} of
    a JSON request (a string value read as typed text), as {parameter: value}."""
    if isinstance(value, dict) and value:
        return {k: parse_value(v) if isinstance(v, str) else v for k, v in value.items()}
    if not isinstance(value, list) or len(value) % 2 or not value:
        raise ArgError("usage: param set BLOCK PARAM VALUE [PARAM VALUE ...]")
    values: dict[str, Any] = {}
    for name, text in zip(value[::2], value[1::2], strict=True):
        if name in values:
            raise ArgError(f"parameter {name!r} is given twice")
        values[name] = parse_value(text)
    return values


def names(value: Any) -> list[str]:
    if isinstance(value, str):
        return [value]
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise ArgError('"names" must be a list of parameter names')
    return value


# ---- the commands ------------------------------------------------------------------------
def param_blocks(local: Any, args: dict[str, Any]) -> dict[str, Any]:
    return {"blocks": [{"id": b.id, "service": b.service, "provider": b.provider}
                       for b in session(local).blocks()]}


def param_list(local: Any, args: dict[str, Any]) -> dict[str, Any]:
    """One block's listing (values as of the loop's last copy), or every block's counts."""
    s = session(local)
    if args["block"]:
        return s.describe(args["block"], None, False)
    found = []
    for block in s.blocks():
        answer = s.query(block, "list")
        found.append({"block": block.id, "service": block.service, "client": block.provider,
                      "parameters": len(answer["parameters"]),
                      "overridden": sum(p["overridden"] for p in answer["parameters"]),
                      "updates": answer["updates"]})
    return {"blocks": found}


def param_get(local: Any, args: dict[str, Any]) -> dict[str, Any]:
    answer = session(local).describe(args["block"], args["name"], wait=args["wait"])
    if args["name"]:
        answer["parameter"] = args["name"]
    return answer


def param_set(local: Any, args: dict[str, Any]) -> dict[str, Any]:
    return session(local).set(args["block"], args["values"])


def param_reset(local: Any, args: dict[str, Any]) -> dict[str, Any]:
    return session(local).reset(args["block"], args["names"])


def param_changes(local: Any, args: dict[str, Any]) -> Iterator[dict[str, Any]]:
    """The block's remembered changes after --since, then with --follow the new ones every
    FOLLOW_PERIOD until stopped; a row {"note"} says how many were no longer remembered."""
    s, since = session(local), args["since"]
    while True:
        answer = s.changes(args["block"], since)
        if answer["changes"] and since and answer["changes"][0]["generation"] > since + 1:
            yield {"note": f"({answer['changes'][0]['generation'] - since - 1} older changes "
                           "are no longer remembered)"}
        yield from answer["changes"]
        since = answer["generation"]
        if not args["follow"] or local.stop.wait(FOLLOW_PERIOD):
            return


def param_save(local: Any, args: dict[str, Any]) -> dict[str, Any]:
    return session(local).save(Path(args["path"]).expanduser())


def param_load(local: Any, args: dict[str, Any]) -> dict[str, Any]:
    return session(local).load(Path(args["path"]).expanduser())


# ---- what the scripting API returns ------------------------------------------------------
def values_of(answer: dict[str, Any]) -> Any:
    """param_get(): the value of the parameter asked for, or {name: value} of all."""
    values = {p["name"]: pythonize(p, p["value"]) for p in answer["parameters"]}
    return values[answer["parameter"]] if "parameter" in answer else values


# ---- text --------------------------------------------------------------------------------
def _json(value: Any) -> list[str]:
    return json.dumps(value, indent=2, ensure_ascii=False).splitlines()


def _json_if_asked(text: Callable[[dict[str, Any]], list[str]]) -> LineFormat:
    """A console format: the answer as JSON with --json, else `text` of it."""

    def lines(answer: dict[str, Any], args: dict[str, Any]) -> list[str]:
        return _json(answer) if args.get("json") else text(answer)

    return lines


def list_lines(answer: dict[str, Any], args: dict[str, Any]) -> list[str]:
    if "parameters" not in answer:  # every block
        if args.get("json"):
            return _json(answer["blocks"])
        rows = [["block", "service", "parameters", "overridden", "updates"]]
        rows += [[f["block"], f["service"], str(f["parameters"]), str(f["overridden"]),
                  str(f["updates"])] for f in answer["blocks"]]
        return table(rows)
    if args.get("json"):
        return _json(answer)
    rows = [["parameter", "type", "value", "override", "range", "description"]]
    for p in answer["parameters"]:
        rows.append([p["name"], type_text(p), value_text(p, p["value"]), state_text(p),
                     range_text(p), p["description"]])
    return table(rows) + [f"configuration refused: {text}"
                          for text in answer.get("config_errors", [])]


def get_lines(answer: dict[str, Any], args: dict[str, Any]) -> list[str]:
    if args.get("json"):
        return _json({k: v for k, v in answer.items() if k != "parameter"})
    params = answer["parameters"]
    if "parameter" in answer:
        return [value_text(params[0], params[0]["value"])]
    lines = []
    for p in params:
        line = f"{p['name']}: {value_text(p, p['value'])}"
        if p["overridden"]:
            line += f"  (overridden by {p['source']}"
            line += ", pending)" if p["pending"] else ")"
        lines.append(line)
    if not answer["live"]:
        lines.append(f"(the loop has not updated within the wait: values as of its update "
                     f"{answer['values_update']})")
    return lines


@_json_if_asked
def set_lines(answer: dict[str, Any]) -> list[str]:
    return [f"{answer['id']}: set {', '.join(answer['set'])} (generation "
            f"{answer['generation']}; in effect at the loop's next update)"]


@_json_if_asked
def reset_lines(answer: dict[str, Any]) -> list[str]:
    return [f"{answer['id']}: reset {', '.join(answer['reset']) or 'nothing (no override)'}"]


def change_lines(row: dict[str, Any], args: dict[str, Any]) -> list[str]:
    if "note" in row:
        return [row["note"]]
    return [json.dumps(row, ensure_ascii=False) if args.get("json") else change_text(row)]


@_json_if_asked
def save_lines(answer: dict[str, Any]) -> list[str]:
    return [f"saved {answer['parameters']} parameters of {answer['blocks']} blocks to "
            f"{answer['path']}"]


@_json_if_asked
def load_lines(answer: dict[str, Any]) -> list[str]:
    return [f"loaded {len(answer['loaded'])} blocks from {answer['path']}"
            + (f": {', '.join(answer['loaded'])}" if answer["loaded"] else "")]


def load_failed(answer: dict[str, Any]) -> str:
    """A load that left blocks out is a failure of the console and the CLI."""
    return "; ".join(answer["errors"])
