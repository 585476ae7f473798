"""The log lines the manager collects (docs/logging.md, "Client logging"): LOG batches of
every client (ln_log, ln.LogHandler) and the lines a `log_level_regex` picks from process
output, in one bounded ring (the oldest go first, counted), with the filters of `ln_manager
log` and waiters for the lines that come next (`log -f`, the web UI's log page)."""

from __future__ import annotations

import asyncio
import fnmatch
import itertools
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from ...tools import protocol as p
from .defaults import LOG_LINES

DEFAULT_CAPACITY = LOG_LINES  # lines kept
LEVELS = {"debug": 10, "info": 20, "warning": 30, "error": 40, "critical": 50}
LEVEL_NAMES = {number: name for name, number in LEVELS.items()}
# ln.h's levels are Python's; other spellings a regex's level group may have
ALIASES = {"warn": 30, "err": 40, "fatal": 50, "crit": 50, "trace": 10, "notice": 20,
           "dbg": 10, "inf": 20, "wrn": 30, "d": 10, "i": 20, "w": 30, "e": 40, "f": 50,
           "c": 50}
FIELD = chr(p.SCHEMA.consts["LOG_FIELD"].value)
END = chr(p.SCHEMA.consts["LOG_END"].value)


class LogBatchError(ValueError):
    """A LOG batch whose entries do not follow docs/protocol.md ("Client logging")."""


def level_number(value: str | int) -> int:
    """A level as a number: a name (any case, also warn/fatal/...) or 10..50; ValueError."""
    if isinstance(value, int) and not isinstance(value, bool):
        number = value
    else:
        text = str(value).strip().lower()
        number = int(text) if text.isdigit() else LEVELS.get(text, ALIASES.get(text, -1))
    if not 10 <= number <= 50:
        raise ValueError(f"unknown log level {value!r}: one of {', '.join(LEVELS)}")
    return number


def level_name(number: int) -> str:
    """The name of a level, or of the next lower named one (Python's custom levels)."""
    return LEVEL_NAMES.get(number - number % 10, "debug") if number >= 10 else "debug"


@dataclass(frozen=True, slots=True)
class LogEntry:
    seq: int
    time_ns: int
    level: int
    source: str  # "client" (ln_log), "output" (a process's output line)
    client: str  # the client's name, or the process's for an output line
    process: str  # the configured process it comes from ("" if none is known)
    host: str
    pid: int
    file: str
    line: int
    logger: str
    text: str

    def to_json(self) -> dict[str, Any]:
        return {"seq": self.seq, "time": self.time_ns / 1e9, "time_ns": self.time_ns,
                "level": self.level, "level_name": level_name(self.level),
                "source": self.source, "client": self.client, "process": self.process,
                "host": self.host, "pid": self.pid, "file": self.file, "line": self.line,
                "logger": self.logger, "text": self.text}


@dataclass(frozen=True)
class LogFilter:
    """What `ln_manager log` shows: lines at `level` and above, of a process or client
    (a name or fnmatch pattern), of a host, containing `grep` (case-insensitive)."""

    level: int = 0
    process: str = ""
    host: str = ""
    grep: str = ""

    def __call__(self, e: LogEntry) -> bool:
        if e.level < self.level:
            return False
        if self.process and not (_match(self.process, e.process)
                                 or _match(self.process, e.client)):
            return False
        if self.host and not _match(self.host, e.host):
            return False
        return not self.grep or self.grep.lower() in e.text.lower()


def _match(pattern: str, name: str) -> bool:
    return bool(name) and (pattern == name or fnmatch.fnmatchcase(name, pattern))


def parse_batch(count: int, entries: str) -> list[tuple[int, int, str, int, str, str]]:
    """The (level, time_ns, file, line, logger, text) of a LOG batch's entries text;
    LogBatchError naming the entry and what is wrong with it."""
    parts = entries.split(END)
    if parts[-1] != "":
        raise LogBatchError(f"entries do not end with LOG_END (0x{ord(END):02X})")
    parts.pop()
    if len(parts) != count:
        raise LogBatchError(f"count is {count} but the entries text holds {len(parts)}")
    out = []
    for index, part in enumerate(parts):
        fields = part.split(FIELD, 5)
        if len(fields) != 6:
            raise LogBatchError(f"entry {index}: {len(fields)} fields, expected 6")
        level, time_ns, file, line, logger, text = fields
        try:
            number = level_number(int(level))
            out.append((number, int(time_ns), file, int(line), logger, text))
        except ValueError as exc:
            raise LogBatchError(f"entry {index}: {exc}") from None
    return out


class LogStore:
    """The ring of recent lines.  Lines get increasing sequence numbers; `query(since=S)`
    gives those after S, `wait(S, timeout)` waits for one.  Drops are counted where they
    happen: `evicted` here (the ring was full), `client_dropped` as each client reports
    its own queue's drops."""

    def __init__(self, capacity: int = DEFAULT_CAPACITY) -> None:
        self._entries: deque[LogEntry] = deque(maxlen=max(1, capacity))
        self._seq = itertools.count(1)
        self.last_seq = 0
        self.evicted = 0
        self.client_dropped: dict[tuple[str, str], int] = {}  # (client, host) -> count
        self._new = asyncio.Event()  # bound to a loop by its first wait (Python >= 3.10)
        # called with each new line (the web UI's live log page)
        self.listeners: list[Callable[[LogEntry], None]] = []
        # (host, pid) -> the configured process of that pid, when the scheduler knows it
        self.process_of: Callable[[str, int], str] = lambda host, pid: ""

    @property
    def capacity(self) -> int:
        return self._entries.maxlen or 0

    def add(self, *, time_ns: int, level: int, source: str, client: str, host: str,
            pid: int = 0, file: str = "", line: int = 0, logger: str = "", text: str = "",
            process: str = "") -> LogEntry:
        seq = next(self._seq)
        entry = LogEntry(seq, time_ns, level, source, client,
                         process or self.process_of(host, pid), host, pid, file, line,
                         logger, text)
        if len(self._entries) == self._entries.maxlen:
            self.evicted += 1
        self._entries.append(entry)
        self.last_seq = seq
        self._new.set()
        for listener in list(self.listeners):
            listener(entry)
        return entry

    def add_batch(self, client: str, host: str, pid: int, dropped: int, count: int,
                  entries: str) -> int:
        """A client's LOG batch (LogBatchError, nothing added, if malformed); the lines
        added."""
        parsed = parse_batch(count, entries)
        self.client_dropped[(client, host)] = dropped
        for level, time_ns, file, line, logger, text in parsed:
            self.add(time_ns=time_ns, level=level, source="client", client=client, host=host,
                     pid=pid, file=file, line=line, logger=logger, text=text)
        return len(parsed)

    def query(self, wanted: LogFilter, since: int = 0, n: int | None = None
              ) -> list[LogEntry]:
        """The lines after `since` that pass the filter, oldest first, the last `n` of them
        (None: all)."""
        found = [e for e in self._after(since) if wanted(e)]
        return found if n is None else found[len(found) - n:] if n > 0 else []

    def _after(self, since: int) -> Iterable[LogEntry]:
        if since <= 0:
            return self._entries
        first = self._entries[0].seq if self._entries else 0
        skip = max(0, since - first + 1)
        return itertools.islice(self._entries, skip, None)

    async def wait(self, since: int, timeout: float) -> None:
        """Until there is a line after `since`, at most `timeout` seconds."""
        while self.last_seq <= since:
            self._new.clear()
            try:
                await asyncio.wait_for(self._new.wait(), timeout)
            except TimeoutError:
                return

    def drops(self) -> list[dict[str, Any]]:
        return [{"client": client, "host": host, "dropped": count}
                for (client, host), count in sorted(self.client_dropped.items()) if count]

