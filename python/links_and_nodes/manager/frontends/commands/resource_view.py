"""The `top` command (docs/introspection.md, "Resources: ln_manager top"): the newest resource
samples of every host and process that the daemons send (processes/resources.py), as tables
for the console, a refreshing view for `ln_manager top` (`--once`, `--json` for scripts), the
web UI's host page and the scope's resource signals."""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from typing import Any

from ....tools.commands.columns import size_text, table
from ....tools.commands.spec import Arg, Command
from ....tools.commands.table import register

_CLEAR = "\x1b[H\x1b[2J"  # cursor home, clear the screen


async def _top(control: Any, args: dict[str, Any]) -> dict[str, Any]:
    sched = control.scheduler
    if sched is None:
        return {"hosts": [], "processes": [], "signals": {}}
    res = sched.resources
    procs = [{"name": name, "state": p.state.value, "node": p.cfg.node, "pid": p.pid,
              "limit": p.limit, **res.process_fields(name, p.pid)}
             for name, p in sorted(sched.procs.items())]
    return {"hosts": res.host_listing(), "processes": procs, "signals": res.signals()}


def _cpu(v: float | None) -> str:
    return "-" if v is None else f"{v:.1f}"


def format_top(result: dict[str, Any], args: dict[str, Any] | None = None) -> list[str]:
    """Hosts (load, CPU, memory, network), then processes (CPU %, RSS, threads, ...)."""
    rows = [["host", "load", "cpu %", "per cpu %", "memory used", "of", "network rx/s",
             "tx/s"]]
    for h in result["hosts"]:
        rx = sum(n["rx"] for n in h["nets"])
        tx = sum(n["tx"] for n in h["nets"])
        rows.append([h["host"], " ".join(f"{x:.2f}" for x in h["load"]), f"{h['cpu']:.1f}",
                     " ".join(f"{c:.0f}" for c in h["cpus"]),
                     size_text(h["mem_total"] - h["mem_available"]), size_text(h["mem_total"]),
                     size_text(rx), size_text(tx)])
    lines = table(rows) if result["hosts"] else ["no resource samples yet"]
    rows = [["process", "state", "node", "pid", "cpu %", "rss", "threads", "fds", "ctx vol",
             "ctx invol", "limit"]]
    for p in result["processes"]:
        sampled = p["rss"] is not None
        rows.append([p["name"], p["state"], p["node"], str(p["pid"] or "-"), _cpu(p["cpu"]),
                     size_text(p["rss"]) if sampled else "-",
                     *(str(p[k]) if sampled else "-"
                       for k in ("threads", "fds", "ctx_voluntary", "ctx_involuntary")),
                     p["limit"]])
    return [*lines, "", *table(rows)]


def _cli_top(mgr: Any, args: dict[str, Any]) -> Iterator[str]:
    """`ln_manager top`: the tables every --interval seconds until Ctrl-C; --once prints them
    once, --json the answer once."""
    while True:
        result = {k: v for k, v in mgr.command("top").items() if k != "ok"}
        if args["json_out"]:
            yield from json.dumps(result, indent=2).splitlines()
            return
        lines = format_top(result)
        if args["once"]:
            yield from lines
            return
        yield _CLEAR + time.strftime("%H:%M:%S") + "  (Ctrl-C ends)"
        yield from lines
        time.sleep(args["interval"])


register(
    Command(
        "top", "resources of every host and process: CPU, memory, threads, load, network",
        "processes", _top,
        (Arg("once", "bool", "print the tables once", default=False, where="cli"),
         Arg("json_out", "bool", "print the answer once as JSON", default=False, where="cli",
             flag="--json"),
         Arg("interval", "float", "seconds between refreshes", default=1.0, low=0.1,
             high=3600, where="cli", error='"interval" must be 0.1..3600 seconds',
             metavar="S")),
        result="hosts: [{host, time, load, cpu, cpus, mem_total, mem_available, swap_total, "
               "swap_free, nets: [{interface, rx, tx}]}], processes: [{name, state, node, "
               "pid, cpu, rss, threads, fds, ctx_voluntary, ctx_involuntary, limit}], "
               "signals: {NAME: value}",
        console_format=format_top, cli_run=_cli_top,
        cli_help="resources of every host and process, refreshed (--once, --json)",
        script="resources", script_result=lambda result: result,
        script_doc="The newest resource samples: {\"hosts\": [...], \"processes\": [...], "
                   "\"signals\": {\"process/NAME/cpu\": value, ...}} (docs/introspection.md)."),
)
