"""The process commands' answers as text, for the console and `ln_manager COMMAND`: tables of
processes, topics, services, hosts and network streams, transitions, what was started."""

from __future__ import annotations

import json
import time
from typing import Any

from ....tools.commands.columns import size_text, table


def bytes_text(n: float) -> str:
    for unit in ("B", "KB", "MB"):
        if n < 1000:
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1000
    return f"{n:.1f} GB"


def format_status(result: dict[str, Any], args: dict[str, Any] | None = None) -> list[str]:
    rows = [["process", "state", "pid", "node", "cpu %", "rss", "threads", "restarts",
             "reason"]]
    for p in result["processes"]:
        cpu, rss = p.get("cpu"), p.get("rss")  # resources (resource_view.py), if sampled
        reason = "; ".join(x for x in (p.get("limit"), p["reason"]) if x)
        rows.append([p["name"], p["state"], str(p["pid"] or "-"), p["node"],
                     "-" if cpu is None else f"{cpu:.1f}",
                     "-" if rss is None else size_text(rss),
                     str(p.get("threads") or "-"), str(p["restarts"]), reason])
    lines = table(rows)
    for st in result["states"]:
        up = {True: "UP", False: "DOWN", None: "unknown"}[st["up"]]
        lines.append(f"state {st['name']}: {up}")
    return lines


def format_network(result: dict[str, Any], args: dict[str, Any] | None = None) -> list[str]:
    """A `network` result as tables: streams, host pairs, pull producers."""
    from .pull_view import format_network as pull_tables

    rows = [["topic", "from", "to", "via", "msgs/s", "bytes/s", "sent", "received",
             "drops", "stale", "rejected", "error"]]
    for s in result["streams"]:
        rows.append([s["topic"], s["src"], s["dst"], s["transport"],
                     f"{s['msgs_per_s']:.1f}", bytes_text(s["bytes_per_s"]), str(s["sent"]),
                     str(s["received"]), str(s["drops"]), str(s["stale"]),
                     str(s.get("rejected", 0)), s["error"]])
    for p in result["problems"]:
        rows.append([p["topic"], p["src"], p["dst"], "-", "-", "-", "-", "-", "-", "-", "-",
                     p["error"]])
    lines = table(rows)
    if result["pairs"]:
        rows = [["from", "to", "topics", "msgs/s", "bytes/s", "drops"]]
        for p in result["pairs"]:
            rows.append([p["src"], p["dst"], str(p["topics"]), f"{p['msgs_per_s']:.1f}",
                         bytes_text(p["bytes_per_s"]), str(p["drops"])])
        lines += table(rows)
    return lines + pull_tables(result.get("pull", []))


def format_processes(verb: str) -> Any:
    """`starting: a, b` and the like: the processes a start/stop/restart concerned."""
    def lines(result: dict[str, Any], args: dict[str, Any]) -> list[str]:
        return [f"{verb}: {', '.join(result['processes'])}"]
    return lines


def format_history(result: dict[str, Any], args: dict[str, Any]) -> list[str]:
    lines = []
    for t in result["transitions"]:
        stamp = time.strftime("%H:%M:%S", time.localtime(t["time"]))
        lines.append(f"{stamp}.{int(t['time'] % 1 * 1000):03d} {t['state']:9} {t['reason']}")
    return lines


def format_topics(result: dict[str, Any], args: dict[str, Any]) -> list[str]:
    rows = [["topic", "md", "publishers", "subscribers", "published"]]
    for t in result["topics"]:
        rows.append([t["name"], t["md_name"], str(t["publishers"]), str(t["subscribers"]),
                     str(t["published"])])
    return table(rows)


def format_services(result: dict[str, Any], args: dict[str, Any]) -> list[str]:
    rows = [["service", "provider", "md", "calls", "errors"]]
    for s in result["services"]:
        rows.append([s["name"], s["provider"], s["md_name"], str(s["calls"]),
                     str(s["errors"])])
    return table(rows)


def format_hosts(result: dict[str, Any], args: dict[str, Any]) -> list[str]:
    rows = [["host", "state", "host id", "data port", "since", "why"]]
    for h in result["hosts"]:
        rows.append([h["name"] + (" *" if h["local"] else ""), h["state"],
                     h["host_id"] or "-", str(h["data_port"] or "-"), f"{h['for_s']:.0f} s",
                     h["error"]])
    return table(rows)


def format_reload(result: dict[str, Any], args: dict[str, Any]) -> list[str]:
    return ["reloaded: " + "; ".join(f"{k}: {', '.join(v) or '-'}"
                                     for k, v in result.items() if k != "ok")]


def format_output(result: dict[str, Any], args: dict[str, Any]) -> list[str]:
    """The console's `output`: each line after the process's name."""
    return [f"{args['name']}: {line['text']}" for line in result["lines"]]


def format_output_plain(result: dict[str, Any], args: dict[str, Any]) -> list[str]:
    return [line["text"] for line in result["lines"]]


def nothing(result: dict[str, Any], args: dict[str, Any]) -> list[str]:
    return []


def json_lines(result: dict[str, Any], args: dict[str, Any]) -> list[str]:
    """The answer of a command without a text view of its own, as indented JSON."""
    return json.dumps({k: v for k, v in result.items() if k != "ok"}, indent=2).splitlines()
