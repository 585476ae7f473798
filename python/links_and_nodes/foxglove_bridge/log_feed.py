"""ln_foxglove's `ln.log` channel: the manager's log lines (docs/logging.md, "Client
logging") as foxglove.Log messages in JSON, so Foxglove's Log panel shows every client's
lines with level, time, process@host and file:line.  Each poll of the bridge takes the
lines that came since the last one (from the line newest at the start)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..tools import foxglove_log
from ..tools.introspection.commands import CommandError


class LogFeed:
    def __init__(self, context: Any) -> None:
        import foxglove

        self.channel = foxglove.Channel(
            foxglove_log.TOPIC, schema=foxglove.Schema(
                name=foxglove_log.SCHEMA_NAME, encoding=foxglove_log.SCHEMA_ENCODING,
                data=foxglove_log.SCHEMA_DATA),
            message_encoding=foxglove_log.MESSAGE_ENCODING, context=context,
            metadata={"kind": "log"})
        self.last: int | None = None
        self.lines = 0
        self.error: str | None = None

    def poll(self, control: Callable[..., dict[str, Any]], say: Callable[[str], None]) -> None:
        """Publish the lines after the last poll's (the first poll only notes where it is)."""
        try:
            result = control("log", since=self.last or 0,
                             n=0 if self.last is None else foxglove_log.LOG_LINES)
        except CommandError as exc:
            if str(exc) != self.error:  # said once per reason
                self.error = str(exc)
                say(f"cannot follow the manager's log lines (will retry): {exc}")
            return
        self.error = None
        if self.last is not None:
            for entry in result["entries"]:
                self.channel.log(foxglove_log.encode(entry), log_time=int(entry["time_ns"]))
                self.lines += 1
        self.last = int(result["last"])

    def close(self) -> None:
        self.channel.close()
