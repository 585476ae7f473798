"""The manager's console: one command per line on stdin, from a terminal or a pipe, answered
on stdout.  Every command goes through control.Control, like remote ones.

    start|stop|restart NAME|GROUP|all    status    output NAME [-n N] [-f]
    history NAME    topics    services    hosts    network    logger ...    reload
    param list|get|set|reset|changes|save|load ...    (param_console.py, docs/parameters.md)
    quit    detach    help
    topic echo|hz|bw|info NAME ...    md show NAME    service call NAME REQUEST
    (these three: introspect_console.py, docs/introspection.md)
"""

from __future__ import annotations

import asyncio
import os
import shlex
import sys
import threading
import time
from collections.abc import Callable
from typing import Any, TextIO

from . import logger_cli
from .control import Control, ControlError
from .introspect_console import execute as introspect
from .introspect_console import stop_watch

HELP = """commands:
  start NAME|GROUP|all     start (dependencies first)
  stop NAME|GROUP|all      stop (dependents first)
  restart NAME|GROUP|all   stop, then start
  status                   every process: state, pid, node, why
  output NAME [-n N] [-f]  last N lines (default 20); -f follows until the next command
  history NAME             every state transition of a process
  topics                   topics with publishers, subscribers and samples
  services                 services with provider, md and calls
  hosts                    every host: its ln_daemon's state, host id, data port
  network                  topics forwarded between hosts: rates, drops, per host pair
  topic echo NAME [-n N] [--field F] [--json] [--full]
                           samples decoded by the md, until done or the next command
  topic hz|bw NAME [--window N] [-n N] [--duration S]
                           rate / bandwidth every second, until done or the next command
  topic info NAME          md, ring, publishers and subscribers with hosts, transports
  md show NAME [-r]        a message definition's text (-r: and the mds it uses)
  service call NAME REQ    call a service; REQ like 'a: 1, b: [1, 2], name: "x"' or JSON
  param list [BLOCK] | get BLOCK [PARAM] | set BLOCK PARAM VALUE | reset BLOCK [PARAM]
  param changes BLOCK | save FILE | load FILE
                           parameter blocks of the processes (docs/parameters.md)
  logger [NAME ...]        topic loggers: NAME add TOPIC [DEPTH] [--divisor K] [--span S],
                           NAME remove [TOPIC], NAME enable [--keep]|disable|status,
                           NAME save FILE (.mcap or .npz; on the manager's host)
  reload                   read the configuration file again
  quit                     stop every process and exit
  detach                   exit, leaving the processes running under their daemons
  help                     this text"""


def _bytes(n: float) -> str:
    for unit in ("B", "KB", "MB"):
        if n < 1000:
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1000
    return f"{n:.1f} GB"


def table(rows: list[list[str]]) -> list[str]:
    if not rows:
        return []
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    return ["  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip()
            for row in rows]


def format_status(result: dict[str, Any]) -> list[str]:
    rows = [["process", "state", "pid", "node", "restarts", "reason"]]
    for p in result["processes"]:
        rows.append([p["name"], p["state"], str(p["pid"] or "-"), p["node"],
                     str(p["restarts"]), p["reason"] or ""])
    lines = table(rows)
    for st in result["states"]:
        up = {True: "UP", False: "DOWN", None: "unknown"}[st["up"]]
        lines.append(f"state {st['name']}: {up}")
    return lines


class Console:
    def __init__(self, control: Control, out: TextIO | None = None) -> None:
        self.control = control
        self.out = out or sys.stdout
        self._follow: Callable[[str, Any], None] | None = None

    def say(self, text: str) -> None:
        self.out.write(text + "\n")
        self.out.flush()

    async def run(self, stream: asyncio.StreamReader) -> None:
        """Read and run commands until `quit`/`detach` or the end of input (which ends only
        the console, not the manager)."""
        try:
            while True:
                raw = await stream.readline()
                if not raw:
                    return
                line = raw.decode(errors="replace").strip()
                self._unfollow()
                if not line or line.startswith("#"):
                    continue
                if await self.execute(line):
                    return
        finally:
            self._unfollow()

    async def execute(self, line: str) -> bool:
        """Run one command line; True when the console should end (quit, detach)."""
        try:
            words = shlex.split(line)
        except ValueError as exc:
            self.say(f"error: {exc}")
            return False
        cmd, args = words[0], words[1:]
        try:
            return await self._dispatch(cmd, args)
        except ControlError as exc:
            self.say(f"error: {exc}")
        return False

    async def _dispatch(self, cmd: str, args: list[str]) -> bool:
        c = self.control
        if cmd in ("help", "?"):
            self.say(HELP)
        elif cmd in ("start", "stop", "restart"):
            if len(args) != 1:
                raise ControlError(f"usage: {cmd} NAME|GROUP|all")
            result = await c.handle({"op": cmd, "target": args[0]})
            past = {"start": "starting", "stop": "stopped", "restart": "restarted"}[cmd]
            self.say(f"{past}: {', '.join(result['processes'])}")
        elif cmd == "status":
            for text in format_status(await c.handle({"op": "status"})):
                self.say(text)
        elif cmd == "output":
            await self._output(args)
        elif cmd == "history":
            if len(args) != 1:
                raise ControlError("usage: history NAME")
            result = await c.handle({"op": "history", "name": args[0]})
            for t in result["transitions"]:
                stamp = time.strftime("%H:%M:%S", time.localtime(t["time"]))
                self.say(f"{stamp}.{int(t['time'] % 1 * 1000):03d} {t['state']:9} "
                         f"{t['reason']}")
        elif cmd == "topics":
            rows = [["topic", "md", "publishers", "subscribers", "published"]]
            for t in (await c.handle({"op": "topics"}))["topics"]:
                rows.append([t["name"], t["md_name"], str(t["publishers"]),
                             str(t["subscribers"]), str(t["published"])])
            for text in table(rows):
                self.say(text)
        elif cmd == "services":
            rows = [["service", "provider", "md", "calls", "errors"]]
            for s in (await c.handle({"op": "services"}))["services"]:
                rows.append([s["name"], s["provider"], s["md_name"], str(s["calls"]),
                             str(s["errors"])])
            for text in table(rows):
                self.say(text)
        elif cmd == "hosts":
            rows = [["host", "state", "host id", "data port", "since", "why"]]
            for h in (await c.handle({"op": "hosts"}))["hosts"]:
                rows.append([h["name"] + (" *" if h["local"] else ""), h["state"],
                             h["host_id"] or "-", str(h["data_port"] or "-"),
                             f"{h['for_s']:.0f} s", h["error"]])
            for text in table(rows):
                self.say(text)
        elif cmd == "network":
            self._network(await c.handle({"op": "network"}))
        elif cmd == "logger":
            await self._logger(args)
        elif cmd in ("topic", "md", "service"):
            await introspect(self, [cmd, *args])
        elif cmd == "param":
            from .param_console import execute as param

            await param(self, args)
        elif cmd == "reload":
            result = await c.handle({"op": "reload"})
            self.say("reloaded: " + "; ".join(f"{k}: {', '.join(v) or '-'}"
                                              for k, v in result.items() if k != "ok"))
        elif cmd in ("quit", "exit", "detach"):
            await c.handle({"op": "detach" if cmd == "detach" else "quit"})
            return True
        else:
            raise ControlError(f"unknown command {cmd!r} (try help)")
        return False

    async def _logger(self, args: list[str]) -> None:
        try:
            op, command = logger_cli.parse(args)
        except logger_cli.UsageError as exc:
            raise ControlError(str(exc)) from None
        if op == "logger_save":  # a file name as typed: relative to the manager's directory
            command["path"] = os.path.abspath(command["path"])
        result = await self.control.handle({"op": op, **command})
        for text in logger_cli.format_result(op, command, result):
            self.say(text)

    def _network(self, result: dict[str, Any]) -> None:
        rows = [["topic", "from", "to", "via", "msgs/s", "bytes/s", "sent", "received",
                 "drops", "stale", "error"]]
        for s in result["streams"]:
            rows.append([s["topic"], s["src"], s["dst"], s["transport"],
                         f"{s['msgs_per_s']:.1f}", _bytes(s["bytes_per_s"]), str(s["sent"]),
                         str(s["received"]), str(s["drops"]), str(s["stale"]), s["error"]])
        for p in result["problems"]:
            rows.append([p["topic"], p["src"], p["dst"], "-", "-", "-", "-", "-", "-", "-",
                         p["error"]])
        for text in table(rows):
            self.say(text)
        if result["pairs"]:
            rows = [["from", "to", "topics", "msgs/s", "bytes/s", "drops"]]
            for p in result["pairs"]:
                rows.append([p["src"], p["dst"], str(p["topics"]), f"{p['msgs_per_s']:.1f}",
                             _bytes(p["bytes_per_s"]), str(p["drops"])])
            for text in table(rows):
                self.say(text)

    async def _output(self, args: list[str]) -> None:
        name, n, follow = None, 20, False
        it = iter(args)
        for word in it:
            if word == "-n":
                value = next(it, "")
                if not (value.isascii() and value.isdigit()):
                    raise ControlError("output: -n needs a number")
                n = int(value)
            elif word == "-f":
                follow = True
            elif name is None:
                name = word
            else:
                raise ControlError("usage: output NAME [-n N] [-f]")
        if name is None:
            raise ControlError("usage: output NAME [-n N] [-f]")
        for line in (await self.control.handle({"op": "output", "name": name, "n": n}))["lines"]:
            self.say(f"{name}: {line['text']}")
        if follow and self.control.scheduler is not None:
            def follow_line(proc: str, line: Any) -> None:
                if proc == name:
                    self.say(f"{name}: {line.text}")
            self._follow = follow_line
            self.control.scheduler.output_listeners.append(follow_line)

    def _unfollow(self) -> None:
        stop_watch(self)  # a topic echo/hz/bw
        if self._follow is not None and self.control.scheduler is not None:
            self.control.scheduler.output_listeners.remove(self._follow)
        self._follow = None


async def stdin_reader() -> asyncio.StreamReader:
    """An asyncio stream over this process's stdin (a terminal, pipe or file)."""
    loop = asyncio.get_running_loop()
    reader = asyncio.StreamReader()
    try:
        await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(reader), sys.stdin)
    except ValueError:  # a regular file: no pipe transport, read it in a thread
        def pump() -> None:
            for raw in sys.stdin.buffer:
                loop.call_soon_threadsafe(reader.feed_data, raw)
            loop.call_soon_threadsafe(reader.feed_eof)
        threading.Thread(target=pump, name="console-stdin", daemon=True).start()
    return reader
