"""The live parts of the WebSocket API (docs/webui.md, "WebSocket API"): subscribe_states,
subscribe_output, subscribe_log, subscribe_topic and unsubscribe.  Each subscription of a
connection answers with what there is now and then sends {"event": KIND, "sub": ID, ...}
until it is ended or the connection closes.  A topic is read by a worker thread with its
own latest-mode subscriber (tools/introspection/client.py TopicReader); the chosen numeric fields of
its samples go out in batches every FLUSH seconds, whole decoded samples at most
VALUES_RATE times a second."""

from __future__ import annotations

import asyncio
import collections
import logging
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from .fields import Extractor, numeric_fields

if TYPE_CHECKING:
    from ..control import Control

FLUSH = 0.015  # seconds between the sample batches of a scope subscription
VALUES_RATE = 10.0  # whole decoded samples per second, at most
MAX_SIGNALS = 64  # fields of one topic subscription
MAX_SUBSCRIPTIONS = 64  # per connection
LOG_KEPT = 2000


class LogBuffer(logging.Handler):
    """The manager's own log records, the last LOG_KEPT, for subscribe_log.  Records of
    other threads (worker threads log too) reach the listeners through the loop."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        super().__init__(logging.DEBUG)
        self.records: collections.deque[dict[str, Any]] = collections.deque(maxlen=LOG_KEPT)
        self.listeners: list[Callable[[dict[str, Any]], None]] = []
        self.setFormatter(logging.Formatter("%(message)s"))
        self.loop = loop
        self.loop_thread = threading.get_ident()

    def emit(self, record: logging.LogRecord) -> None:
        try:
            entry = {"time": record.created, "level": record.levelname.lower(),
                     "text": self.format(record)}
        except Exception:  # noqa: BLE001 - a broken record must not break logging
            return
        if threading.get_ident() == self.loop_thread:
            self._keep(entry)
        elif not self.loop.is_closed():
            self.loop.call_soon_threadsafe(self._keep, entry)

    def _keep(self, entry: dict[str, Any]) -> None:
        self.records.append(entry)
        for listener in list(self.listeners):
            listener(entry)


def _error(text: str) -> Exception:
    from ....tools.commands import ControlError

    return ControlError(text)


class Subscriptions:
    """The subscriptions of one WebSocket connection; `send` queues one event."""

    def __init__(self, control: Control, log: LogBuffer,
                 send: Callable[[dict[str, Any], bool], None]) -> None:
        self.control = control
        self.log = log
        self.send = send  # (event, droppable)
        self._next = 1
        self._undo: dict[int, Callable[[], None]] = {}

    def _new(self, undo: Callable[[], None]) -> int:
        if len(self._undo) >= MAX_SUBSCRIPTIONS:
            raise _error(f"at most {MAX_SUBSCRIPTIONS} subscriptions per connection")
        sub = self._next
        self._next += 1
        self._undo[sub] = undo
        return sub

    def close(self) -> None:
        for undo in self._undo.values():
            undo()
        self._undo.clear()

    async def unsubscribe(self, command: dict[str, Any]) -> dict[str, Any]:
        sub = command.get("sub")
        undo = self._undo.pop(sub, None) if isinstance(sub, int) else None
        if undo is None:
            raise _error(f"no subscription {sub!r}")
        undo()
        return {}

    def _sched(self) -> Any:
        sched = self.control.scheduler
        if sched is None:
            raise _error("this manager runs no configuration (start it with -c FILE)")
        return sched

    async def subscribe_states(self, command: dict[str, Any]) -> dict[str, Any]:
        """Every transition of every process, with the process's row after it."""
        sched = self._sched()
        box: list[int] = []

        def changed(name: str, t: Any) -> None:
            rt = sched.procs.get(name)
            self.send({"event": "state", "sub": box[0], "name": name,
                       "process": rt.as_dict() if rt is not None else None,
                       "transition": {"time": t.time, "state": t.state.value,
                                      "reason": t.reason}}, False)

        sched.transition_listeners.append(changed)
        box.append(self._new(lambda: _remove(sched.transition_listeners, changed)))
        return {"sub": box[0], "processes": sched.status()}

    async def subscribe_output(self, command: dict[str, Any]) -> dict[str, Any]:
        """New output lines of one process (after the last `n` it has)."""
        sched = self._sched()
        name = command.get("name")
        if not isinstance(name, str) or name not in sched.procs:
            raise _error(f"no process named {name!r}")
        n = command.get("n", 1000)
        if isinstance(n, bool) or not isinstance(n, int) or not 0 <= n <= 10000:
            raise _error('"n" must be 0..10000')
        box: list[int] = []

        def line(proc: str, event: Any) -> None:
            if proc == name:
                self.send({"event": "output", "sub": box[0], "name": proc,
                           "line": {"time": event.time, "stream": event.stream,
                                    "text": event.text}}, False)

        sched.output_listeners.append(line)
        box.append(self._new(lambda: _remove(sched.output_listeners, line)))
        return {"sub": box[0], "lines": [{"time": x.time, "stream": x.stream, "text": x.text}
                                         for x in sched.output(name, n)],
                "transitions": [{"time": t.time, "state": t.state.value, "reason": t.reason}
                                for t in sched.history(name)]}

    async def subscribe_log(self, command: dict[str, Any]) -> dict[str, Any]:
        box: list[int] = []

        def record(entry: dict[str, Any]) -> None:
            self.send({"event": "log", "sub": box[0], **entry}, False)

        self.log.listeners.append(record)
        box.append(self._new(lambda: _remove(self.log.listeners, record)))
        return {"sub": box[0], "records": list(self.log.records)}

    async def subscribe_logs(self, command: dict[str, Any]) -> dict[str, Any]:
        """The log lines of clients and process output (registry/logs.py): the last `n`,
        then each new one as {"event": "logs", "sub", ...the line}."""
        from ...registry.logs import LogFilter

        store = self.control.core.logs
        box: list[int] = []

        def line(entry: Any) -> None:
            self.send({"event": "logs", "sub": box[0], **entry.to_json()}, False)

        store.listeners.append(line)
        box.append(self._new(lambda: _remove(store.listeners, line)))
        n = int(command.get("n", 1000))
        return {"sub": box[0], "entries": [e.to_json() for e in
                                           store.query(LogFilter(), 0, n)]}

    async def subscribe_topic(self, command: dict[str, Any]) -> dict[str, Any]:
        """{"name", "fields": [paths]}: batches {"event": "samples", "t": [publish s],
        "seq": [..], "v": [[field 0 values], ...]}; without "fields": {"event": "sample",
        "seq", "publish_time", "data"} (decoded) at most VALUES_RATE per second."""
        from ....tools.introspection.commands import (
            CommandError,
            Context,
            topic_info,
            topic_layout,
        )

        name = command.get("name")
        if not isinstance(name, str) or not name:
            raise _error('"name" must be a non-empty string')
        paths = command.get("fields")
        if paths is not None and (not isinstance(paths, list) or not paths
                                  or len(paths) > MAX_SIGNALS
                                  or not all(isinstance(x, str) for x in paths)):
            raise _error(f'"fields" must be a list of 1..{MAX_SIGNALS} field paths')
        address = getattr(self.control, "manager_address", None)
        if not address:
            raise _error("this manager has no address for its own clients")
        loop = asyncio.get_running_loop()
        from ....tools.commands.from_thread import loop_control

        stop = threading.Event()
        ctx = Context(loop_control(self.control, loop, CommandError), address,
                      lambda _line: None, stop, client_prefix="ln_webui")

        def prepare() -> tuple[dict[str, Any], Any, Extractor | None]:
            info = topic_info(ctx, name)
            md = topic_layout(info)
            if paths is None:
                return info, md, None
            known = {f.path: f for f in numeric_fields(md.struct)}
            missing = [x for x in paths if x not in known]
            if missing:
                raise CommandError(f"topic {name!r}: no numeric field {missing[0]!r}")
            return info, md, Extractor([known[x] for x in paths])

        try:
            info, md, extract = await asyncio.to_thread(prepare)
        except CommandError as exc:
            raise _error(str(exc)) from None
        sub = self._new(stop.set)
        thread = threading.Thread(target=self._feed, daemon=True, name=f"webui-topic-{name}",
                                  args=(ctx, info, md, extract, sub, loop))
        thread.start()
        return {"sub": sub, "name": name, "md_name": info["md_name"],
                "fields": paths or []}

    def _feed(self, ctx: Any, info: dict[str, Any], md: Any, extract: Extractor | None,
              sub: int, loop: asyncio.AbstractEventLoop) -> None:
        from ....tools.introspection import values as fmt
        from ....tools.introspection.commands import CommandError, follow, open_reader

        def deliver(event: dict[str, Any]) -> None:
            if not ctx.stop.is_set():
                self.send(event, True)

        try:
            with open_reader(ctx, info, "webui") as reader:
                t: list[float] = []
                seqs: list[int] = []
                cols: list[list[float]] = [[] for _ in (extract.fields if extract else [])]
                last = time.monotonic()
                for sample in follow(ctx, reader, info["name"]):
                    now = time.monotonic()
                    if extract is None:
                        if now - last >= 1.0 / VALUES_RATE:
                            last = now
                            value = fmt.jsonable(fmt.decode(md.struct, sample.data))
                            loop.call_soon_threadsafe(deliver, {
                                "event": "sample", "sub": sub, "seq": sample.seq,
                                "publish_time": sample.timestamp_ns / 1e9, "data": value})
                        continue
                    t.append(sample.timestamp_ns / 1e9)
                    seqs.append(sample.seq)
                    for col, v in zip(cols, extract(sample.data), strict=True):
                        col.append(v)
                    if now - last >= FLUSH:
                        last = now
                        event = {"event": "samples", "sub": sub, "t": t, "seq": seqs,
                                 "v": [fmt.jsonable(c) for c in cols]}
                        loop.call_soon_threadsafe(deliver, event)
                        t, seqs, cols = [], [], [[] for _ in cols]
        except CommandError as exc:
            loop.call_soon_threadsafe(deliver, {"event": "error", "sub": sub,
                                                "error": str(exc)})
        except Exception as exc:  # noqa: BLE001 - a bug of ours: say it, keep running
            logging.getLogger("ln_manager").exception("web UI topic feed failed")
            loop.call_soon_threadsafe(deliver, {"event": "error", "sub": sub,
                                                "error": f"internal error: {exc!r}"})


def register_streams() -> None:
    """Put the subscriptions into the command table: commands of a live connection (the
    session Control.handle gets is the connection's Subscriptions)."""
    from ....tools.commands import Arg, Command, command, register

    def entry(name: str, help: str, args: tuple[Any, ...], result: str) -> Command:
        async def handler(control: Any, values: dict[str, Any],
                          session: Subscriptions) -> dict[str, Any]:
            return await getattr(session, name)(values)  # type: ignore[no-any-return]
        return Command(name, help, "webui", handler, args, result=result, session=True,
                       console=False, cli=False, script="")

    process = Arg("name", "str", "a process", required=True, nonempty=True)
    entries = [
        entry("subscribe_states", "every process's transitions, live", (),
              "{sub, processes}; events {event: state, name, process, transition}"),
        entry("subscribe_output", "a process's new output lines, live",
              (process, Arg("n", "int", "lines of the past first", default=1000, low=0,
                            high=10000)),
              "{sub, lines, transitions}; events {event: output, name, line}"),
        entry("subscribe_log", "the manager's own log messages, live", (),
              "{sub, records}; events {event: log, time, level, text}"),
        entry("subscribe_logs", "the log lines of clients and process output, live",
              (Arg("n", "int", "lines of the past first", default=1000, low=0,
                   high=20000),),
              "{sub, entries}; events {event: logs, seq, time, level, level_name, client, "
              "process, host, file, line, logger, text}"),
        entry("subscribe_topic", "a topic's samples: chosen numeric fields in batches, or "
                                 "whole decoded samples",
              (Arg("name", "str", "the topic", required=True, nonempty=True),
               Arg("fields", "json", "numeric field paths (none: whole samples)",
                   nullable=True)),
              "{sub, name, md_name, fields}; events {event: samples, t, seq, v} or "
              "{event: sample, seq, publish_time, data}"),
        entry("unsubscribe", "end a subscription of this connection",
              (Arg("sub", "int", "the subscription", required=True),), "{}"),
    ]
    register(*[e for e in entries if command(e.name) is None])


def _remove(listeners: list[Any], item: Any) -> None:
    if item in listeners:
        listeners.remove(item)
