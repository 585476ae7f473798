"""Text views of pull topics for the console and `ln_manager network|pull`: the producers'
ports and topics with their counters (the "pull" part of the network view), and the list of
served topics with their NDN names."""

from __future__ import annotations

from typing import Any

from ....tools.commands.spec import Command
from ....tools.commands.table import register

TOPIC_COUNTERS = ("latest_seq", "interests", "syncs", "data", "nacks", "parked", "expired",
                  "duplicates", "overflow")


def _table(rows: list[list[str]]) -> list[str]:
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    return ["  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip()
            for row in rows]


def format_network(hosts: list[dict[str, Any]]) -> list[str]:
    """The "pull" part of a network result: a ports table and a topics table ([] when no
    topic is served)."""
    if not hosts:
        return []
    ports = [["pull host", "address", "port", "packets", "bad", "unknown", "other", "error"]]
    topics = [["pull topic", "host", "port", "latest", "interests", "syncs", "data", "nacks",
               "parked", "expired", "dups", "overflow", "error"]]
    for h in hosts:
        if h["error"]:
            ports.append([h["host"], "-", "-", "-", "-", "-", "-", h["error"]])
        for p in h["ports"]:
            ports.append([h["host"], p["address"] or "0.0.0.0", str(p["port"]),
                          str(p["packets"]), str(p["bad"]), str(p["unknown"]), str(p["other"]),
                          p["last_error"]])
        for t in h["topics"]:
            topics.append([t["topic"], h["host"], str(t["port"]),
                           *(str(t[c]) for c in TOPIC_COUNTERS), t["error"]])
    return _table(ports) + _table(topics)


def format_listing(topics: list[dict[str, Any]]) -> list[str]:
    if not topics:
        return ["no pull topics"]
    rows = [["topic", "host", "name", "address", "port", "history", "signature", "error"]]
    for t in topics:
        rows.append([t["topic"], t["host"], t["name"], t["address"], str(t["port"]),
                     str(t["history"]), t["signature"], t["error"]])
    return _table(rows)


async def _pull(control: Any, args: dict[str, Any]) -> dict[str, Any]:
    return dict(await control.pull_topics(args))


register(Command(
    "pull", "pull topics served by the daemons: NDN name, port, host", "topics", _pull,
    result="topics: [{topic, host, name, address, port, history, signature, error}]",
    console_format=lambda result, args: format_listing(result["topics"]),
    cli_help="pull topics served by the daemons: NDN name, port, host (docs/pull.md)",
    json_view=lambda result: result["topics"],
    script_result=lambda result: result["topics"],
    script_doc="The pull topics served by the daemons (docs/pull.md): topic, host, name, "
               "address, port, history, signature, error."))
