"""ln_record --logs: the manager's log lines (docs/logging.md, "Client logging") written as
foxglove.Log messages (JSON) on channel `ln.log` beside the topics, into the recorder's
SplitWriter under its lock, so Foxglove's Log panel shows them.  A thread follows the
manager's `log` command from the line that was newest at the start."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from ..tools import foxglove_log

WAIT = 0.5  # seconds one `log` request waits for new lines (also how soon stop() is seen)
ALL = foxglove_log.LOG_LINES  # with since 0 (no line yet) `n` still limits the answer


class LogChannel:
    """The ln.log channel for SplitWriter.add_channel (re-added in every file)."""

    def add_to(self, writer: Any, topic: str) -> int:
        return int(writer.add_channel(
            topic, schema_name=foxglove_log.SCHEMA_NAME,
            schema_encoding=foxglove_log.SCHEMA_ENCODING,
            schema_data=foxglove_log.SCHEMA_DATA,
            message_encoding=foxglove_log.MESSAGE_ENCODING, metadata={"kind": "log"}))


class LogRecording:
    """Records the manager's log lines through `recorder` (its `out`, `lock`, `error`,
    `_fail`) until stop(); `connect(address)` gives a scripting connection."""

    def __init__(self, recorder: Any, address: str, connect: Callable[[str], Any],
                 say: Callable[[str], None] = lambda text: None) -> None:
        self.recorder = recorder
        self.say = say
        self.lines = 0
        self._connect = connect
        self._address = address
        with recorder.lock:
            self.channel = recorder.out.add_channel(foxglove_log.TOPIC, LogChannel())
        self._stop = threading.Event()
        self._mgr = connect(address)
        self._last = int(self._mgr.command("log", n=0)["last"])
        self._thread = threading.Thread(target=self._run, daemon=True, name="ln_record logs")
        self._thread.start()
        say(f"recording the manager's log lines on channel '{foxglove_log.TOPIC}'")

    def _run(self) -> None:
        error = ""
        while not self._stop.is_set():
            try:
                if self._mgr is None:
                    self._mgr = self._connect(self._address)
                result = self._mgr.command("log", since=self._last, timeout=WAIT,
                                           n=ALL, wait=WAIT)
            except Exception as exc:  # noqa: BLE001 - ManagerError, lost connection: retry
                if str(exc) != error:
                    error = str(exc)
                    self.say(f"cannot follow the manager's log lines (will retry): {exc}")
                if self._mgr is not None:
                    self._mgr.close()
                    self._mgr = None
                self._stop.wait(WAIT)
                continue
            error = ""
            self._write(result["entries"])
            self._last = int(result["last"])

    def _write(self, entries: list[dict[str, Any]]) -> None:
        rec = self.recorder
        try:
            with rec.lock:
                if rec.error is not None:
                    return
                for entry in entries:
                    rec.out.write(self.channel, self.lines, int(entry["time_ns"]),
                                  foxglove_log.encode(entry))
                    self.lines += 1
        except OSError as exc:
            rec._fail(f"cannot write {rec.out.writer.path}: {exc}")

    def stop(self) -> None:
        """Stop following, then write the lines the manager got until now."""
        self._stop.set()
        self._thread.join()
        if self._mgr is not None:
            try:
                self._write(self._mgr.command("log", since=self._last, n=ALL)["entries"])
            except Exception as exc:  # noqa: BLE001 - the manager is gone: nothing more
                self.say(f"cannot take the last log lines: {exc}")
            self._mgr.close()
