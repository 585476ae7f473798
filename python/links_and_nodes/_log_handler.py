"""ln.LogHandler: a logging.Handler that sends Python log records to the manager through
libln's client logging (ln_log_text; docs/logging.md, "Client logging") with their level,
file:line and logger name.  Like ln_log it never blocks: a record that finds the client's
queue full is dropped and counted (`dropped`)."""

from __future__ import annotations

import ctypes
import logging
from typing import TYPE_CHECKING

from . import _clientlib as C
from .errors import LnError

if TYPE_CHECKING:
    from ._client import client


def ln_level(levelno: int) -> int:
    """A Python level as one of ln.h's (10..50): custom levels are clamped."""
    return min(50, max(10, levelno))


class LogHandler(logging.Handler):
    """`logging.getLogger().addHandler(ln.LogHandler(clnt))`: records of `level` and above
    go to the manager as log lines of `clnt` (`ln_manager log`, the web UI's log page).  The
    text is the handler's formatting of the record (its message alone unless a Formatter is
    set)."""

    def __init__(self, clnt: client, level: int = logging.NOTSET) -> None:
        super().__init__(level)
        self.client = clnt

    def emit(self, record: logging.LogRecord) -> None:
        try:
            text = self.format(record)
            code = C.ln_log_text(self.client.handle, ln_level(record.levelno),
                                 record.pathname.encode("utf-8", "replace"), record.lineno,
                                 record.name.encode("utf-8", "replace"),
                                 text.encode("utf-8", "replace"))
            if code < 0 and code != C.LN_EAGAIN:
                C._check(code, None, ())
        except Exception:  # as logging wants: a failing handler never raises into the caller
            self.handleError(record)

    @property
    def queued(self) -> int:
        """Lines the client queued so far (of every sender of the client)."""
        return self._counts()[0]

    @property
    def dropped(self) -> int:
        """Lines the client dropped so far: its queue was full or the manager away."""
        return self._counts()[1]

    def _counts(self) -> tuple[int, int]:
        queued, dropped = ctypes.c_uint64(), ctypes.c_uint64()
        C.ln_log_counts(self.client.handle, ctypes.byref(queued), ctypes.byref(dropped))
        return queued.value, dropped.value

    def flush(self, timeout: float = 5.0) -> None:
        """Wait until what was queued has been sent (at most `timeout` seconds; no error if
        the client is closed or the time passes)."""
        try:
            C.ln_log_flush(self.client.handle, timeout)
        except (ValueError, LnError):
            pass
