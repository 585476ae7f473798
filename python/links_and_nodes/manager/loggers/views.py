"""The text of the `logger ...` commands' answers in the console and `ln_manager logger ...`
(docs/logging.md); their words come from the command table (commands.py)."""

from __future__ import annotations

from typing import Any

from ...tools.commands.columns import table


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
