"""The `logger` command line, shared by the console and `ln_manager logger ...`
(docs/logging.md): the words after `logger` become one control command, and its answer
becomes text.

    logger                                   every logger
    logger NAME add TOPIC [DEPTH] [--divisor K] [--span S]
    logger NAME remove [TOPIC]               a topic pattern, or the whole logger
    logger NAME enable [--keep] | disable | status
    logger NAME save FILE                    .mcap or .npz
"""

from __future__ import annotations

import argparse
from typing import Any


USAGE = ("usage: logger [NAME add TOPIC [DEPTH] [--divisor K] [--span S] | NAME remove [TOPIC]"
         " | NAME enable [--keep] | NAME disable | NAME status | NAME save FILE]")
DEFAULT_DEPTH = 1000


class UsageError(Exception):
    """Words that are no logger command; the text says what is expected."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> Any:  # never exit from inside the console
        raise UsageError(f"logger: {message}\n{USAGE}")


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="logger", add_help=False)
    p.add_argument("name")
    sub = p.add_subparsers(dest="action", required=True, parser_class=_Parser)
    add = sub.add_parser("add", add_help=False)
    add.add_argument("topic")
    add.add_argument("depth", nargs="?", type=int, default=DEFAULT_DEPTH)
    add.add_argument("--divisor", type=int, default=1)
    add.add_argument("--span", type=float, default=0.0)
    sub.add_parser("remove", add_help=False).add_argument("topic", nargs="?", default="")
    sub.add_parser("enable", add_help=False).add_argument("--keep", action="store_true")
    sub.add_parser("disable", add_help=False)
    sub.add_parser("status", add_help=False)
    sub.add_parser("save", add_help=False).add_argument("file")
    return p


def parse(words: list[str]) -> tuple[str, dict[str, Any]]:
    """(op, arguments) of a control command; `save` gives the file as written (the caller
    decides where it is written)."""
    if not words:
        return "logger_list", {}
    args = _parser().parse_args(words)
    name = {"name": args.name}
    if args.action == "add":
        return "logger_add", {**name, "topic": args.topic, "depth": args.depth,
                              "divisor": args.divisor, "span": args.span}
    if args.action == "remove":
        return "logger_remove", {**name, "topic": args.topic}
    if args.action == "enable":
        return "logger_enable", {**name, "keep": args.keep}
    if args.action == "save":
        return "logger_save", {**name, "path": args.file}
    return f"logger_{args.action}", name


def table(rows: list[list[str]]) -> list[str]:
    from .console import table as columns  # the console's layout (it imports this module)

    return columns(rows)


def format_result(op: str, args: dict[str, Any], result: dict[str, Any]) -> list[str]:
    if op == "logger_list":
        rows = [["logger", "enabled", "patterns", "topics"]]
        rows += [[lg["name"], "yes" if lg["enabled"] else "no", str(lg["patterns"]),
                  str(lg["topics"])] for lg in result["loggers"]]
        return table(rows) if len(rows) > 1 else ["no loggers"]
    if op in ("logger_status", "logger_add"):
        return format_status(result)
    if op == "logger_save":
        return format_saved(result)
    verb = {"logger_remove": "removed", "logger_enable": "enabled",
            "logger_disable": "disabled"}.get(op, "done")
    what = f" {args['topic']!r} of" if args.get("topic") else ""
    return [f"{verb}:{what} logger {args['name']}"]


def format_status(result: dict[str, Any]) -> list[str]:
    lines = [f"logger {result['name']}: {'enabled' if result['enabled'] else 'disabled'}; "
             + ", ".join(f"{p['pattern']} (depth {p['depth']}"
                         + (f", divisor {p['divisor']}" if p["divisor"] > 1 else "")
                         + (f", span {p['span']:g} s" if p["span"] else "") + ")"
                         for p in result["patterns"])]
    rows = [["topic", "host", "stored", "received", "missed", "skipped", "dropped", "error"]]
    for t in result["topics"]:
        rows.append([t["topic"], t["host"], str(t.get("stored", "-")),
                     str(t.get("received", "-")), str(t.get("missed", "-")),
                     str(t.get("skipped", "-")), str(t.get("dropped", "-")), t["error"]])
    return lines + (table(rows) if len(rows) > 1 else ["no topic with a publisher yet"])


def format_saved(result: dict[str, Any]) -> list[str]:
    lines = [f"saved {result['path']}"]
    for topic, t in result["topics"].items():
        lines.append(f"  {topic}: {t['samples']} samples ({t['md_name']}), missed "
                     f"{t['missed']}, dropped {t['dropped']}, gaps {t['gaps']}")
    return lines
