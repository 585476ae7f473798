"""What the console and `ln_manager` print of the introspection commands' rows and answers
(docs/introspection.md): a sample of `topic echo`, a line of `topic hz|bw`, `topic info`,
`md show`, the response of `service call`; with --json as JSON.  The value formatting
(values.py, which needs ln_generate) is imported by the views that print values, so that the
command table, which names these views, stays light."""

from __future__ import annotations

import json
from typing import Any

from .stats import PeriodStats, bw_line, hz_line


def echo_lines(record: dict[str, Any], args: dict[str, Any]) -> list[str]:
    """One sample: its header and values (a field's value alone, one line), or JSON."""
    from . import values as fmt

    if args.get("json"):
        return [fmt.json_line(record)]
    value = record["data"]
    lines = fmt.format_any(value, bool(args.get("full")))
    if record.get("field") is None or fmt.is_block(value):
        lines.insert(0, fmt.header(record["seq"], record["publish_time_ns"]))
    return lines


def _rate(row: dict[str, Any], bandwidth: bool) -> list[str]:
    if row["stats"] is None:
        if row["final"]:
            return ["no rate: fewer than 2 samples"]
        return ["no new samples" if not row["new"] else "waiting for a second sample"]
    if not row["final"] and not row["new"]:
        return ["no new samples"]
    stats = PeriodStats(**row["stats"])
    return [bw_line(stats, row["message_size"]) if bandwidth else hz_line(stats)]


def hz_lines(row: dict[str, Any], args: dict[str, Any]) -> list[str]:
    return _rate(row, False)


def bw_lines(row: dict[str, Any], args: dict[str, Any]) -> list[str]:
    return _rate(row, True)


def rate_result(rows: list[dict[str, Any]], bandwidth: bool = False) -> dict[str, Any]:
    """What topic_hz() / topic_bw() return: the statistics of the last row (of the whole
    run), zero without two samples; topic_bw() also message_size and bytes_per_s."""
    last = rows[-1] if rows else {"stats": None, "message_size": 0}
    stats = last["stats"] or PeriodStats(0, 0, 0, 0.0, 0.0, None, None, None, None).as_dict()
    if not bandwidth:
        return dict(stats)
    size = int(last["message_size"])
    return {**stats, "message_size": size, "bytes_per_s": stats["rate_hz"] * size}


def info_view(result: dict[str, Any], args: dict[str, Any]) -> list[str]:
    from . import values as fmt

    if args.get("json"):
        return json.dumps({k: v for k, v in result.items() if k != "ok"},
                          indent=2).splitlines()
    return fmt.info_lines(result)


def md_lines(result: dict[str, Any], args: dict[str, Any]) -> list[str]:
    from .commands import md_text

    return md_text(result).removesuffix("\n").split("\n")


def response_lines(row: dict[str, Any], args: dict[str, Any]) -> list[str]:
    from . import values as fmt

    if args.get("json"):
        return [fmt.json_line(row["response"])]
    return fmt.format_block(row["response"], bool(args.get("full"))) or ["{}"]
