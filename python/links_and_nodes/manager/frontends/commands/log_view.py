"""The `log` command (docs/introspection.md, "Log lines"): the lines the manager collected
from clients (ln_log, ln.LogHandler) and from process output (`log_level_regex`), filtered
by level, process, host and text; `-f` follows them (the console until the next command,
`ln_manager log -f` until Ctrl-C, asking again for the lines after the last one)."""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

from ....tools.commands import Arg, ArgError, Command, register
from ...registry.defaults import LOG_LINES

MAX_LINES = LOG_LINES
FOLLOW_WAIT = 5.0  # seconds one request of `log -f` waits for new lines


def _level(value: str) -> str:
    from ...registry.logs import level_name, level_number

    try:
        return level_name(level_number(value))
    except ValueError as exc:
        raise ArgError(str(exc), "EINVAL") from None


ARGS = (
    Arg("level", "str", "only lines at this level and above (debug, info, warning, error, "
        "critical)", default="debug", check=_level, metavar="LEVEL"),
    Arg("process", "str", "only lines of this process or client (a name or pattern)",
        default="", metavar="P"),
    Arg("host", "str", "only lines of this host (a name or pattern)", default="",
        metavar="H"),
    Arg("grep", "str", "only lines containing this text (case-insensitive)", default="",
        metavar="TEXT"),
    Arg("n", "int", "at most the last N lines", default=100, flag="-n", low=0,
        high=MAX_LINES, error=f'"n" must be 0..{MAX_LINES}'),
    Arg("since", "int", "only lines after this sequence number (an answer's last)",
        default=0, low=0),
    Arg("timeout", "float", "seconds to wait for a line after `since` when there is none",
        default=0.0, low=0, high=60, error='"timeout" must be 0..60 seconds', metavar="S"),
    Arg("follow", "bool", "then follow new lines (until the next command / Ctrl-C)",
        flag="-f", where="text", default=False),
    Arg("as_json", "bool", "each line as a JSON object", flag="--json", where="cli",
        default=False),
)


def _filter(args: dict[str, Any]) -> Any:
    """The registry's LogFilter of the command's level, process, host and grep."""
    from ...registry.logs import LogFilter, level_number

    return LogFilter(level_number(args["level"]), args["process"], args["host"], args["grep"])


async def log_lines(control: Any, args: dict[str, Any]) -> dict[str, Any]:
    store = control.core.logs
    wanted = _filter(args)
    since = args["since"]
    if args["timeout"] > 0 and since >= store.last_seq:
        await store.wait(since, args["timeout"])
    entries = store.query(wanted, since, args["n"] if since == 0 else None)
    return {"entries": [e.to_json() for e in entries], "last": store.last_seq,
            "evicted": store.evicted, "capacity": store.capacity, "dropped": store.drops()}


def format_entry(e: dict[str, Any]) -> str:
    stamp = time.strftime("%H:%M:%S", time.localtime(e["time"]))
    ms = int(e["time"] * 1000) % 1000
    who = e["process"] or e["client"]
    place = f" {e['file']}:{e['line']}" if e["file"] else ""
    logger = f" [{e['logger']}]" if e["logger"] else ""
    return (f"{stamp}.{ms:03d} {e['level_name'].upper():8} {who}@{e['host']}{place}"
            f"{logger}: {e['text']}")


def format_log(result: dict[str, Any], args: dict[str, Any]) -> list[str]:
    lines = [format_entry(e) for e in result["entries"]]
    notes = [f"{d['client']}@{d['host']}: {d['dropped']} dropped" for d in result["dropped"]]
    if result["evicted"]:
        notes.append(f"manager: {result['evicted']} oldest lines evicted (keeps "
                     f"{result['capacity']})")
    if notes and not args.get("since"):
        lines.append("(" + "; ".join(notes) + ")")
    return lines


def _request(args: dict[str, Any]) -> dict[str, Any]:
    return {name: args[name] for name in ("level", "process", "host", "grep", "n", "since",
                                          "timeout")}


def _cli_log(mgr: Any, args: dict[str, Any]) -> Iterator[str]:
    """`ln_manager log [-f]`: the last lines, then (-f) the new ones as they come."""
    import json

    result = mgr.command("log", **_request(args))
    show = (lambda r: [json.dumps(e, ensure_ascii=False) for e in r["entries"]]) \
        if args.get("as_json") else (lambda r: format_log(r, args))
    yield from show(result)
    while args["follow"]:
        request = {**_request(args), "since": result["last"], "timeout": FOLLOW_WAIT}
        result = mgr.command("log", wait=FOLLOW_WAIT, **request)
        yield from show(result)


async def _console_log(console: Any, args: dict[str, Any]) -> None:
    result = await console.control.handle({"op": "log", **_request(args)})
    for text in format_log(result, args):
        console.say(text)
    if not args["follow"]:
        return
    store = console.control.core.logs
    wanted = _filter(args)

    def follow(entry: Any) -> None:
        if wanted(entry):
            console.say(format_entry(entry.to_json()))

    store.listeners.append(follow)
    console.hold_watch(lambda: store.listeners.remove(follow))


register(
    Command(
        "log", "log lines of clients and process output: level, process, host, text; -f "
               "follows", "processes", log_lines, ARGS,
        result="entries: [{seq, time, level, level_name, source, client, process, host, "
               "pid, file, line, logger, text}], last, evicted, capacity, dropped: "
               "[{client, host, dropped}]",
        console_run=_console_log, cli_run=_cli_log,
        cli_help="log lines collected from clients and process output (-f follows)",
        script_wait="timeout", script_result=lambda result: result["entries"],
        script_doc="The log lines the manager collected (ln_log, ln.LogHandler, "
                   "log_level_regex), oldest first: dicts with seq, time, level, "
                   "level_name, source, client, process, host, pid, file, line, logger, "
                   "text."),
)
