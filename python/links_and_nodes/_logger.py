"""`clnt.get_logger(name)`: a topic logger of the manager seen from a Python client
(docs/logging.md).  Every method is one control command on the client's connection;
`download()` fetches each topic's samples host by host and merges them in publish order.

    lg = clnt.get_logger("arm")
    lg.add_topic("arm.state", 10000, divisor=1)
    lg.enable(); ...; lg.disable()
    data = lg.download()          # {"arm.state": numpy structured array}
    lg.save("/tmp/arm.mcap")      # or .npz, written here
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from . import logger_files


class logger:  # noqa: N801 - the LN name
    def __init__(self, clnt: Any, name: str) -> None:
        self.clnt = clnt
        self.name: str = clnt.control("logger_open", name=name)["name"]

    def _do(self, op: str, **args: Any) -> dict[str, Any]:
        return self.clnt.control(op, name=self.name, **args)

    def add_topic(self, topic: str, depth: int, divisor: int = 1, span: float = 0.0) -> None:
        """Log `topic` (a name or fnmatch pattern) `depth` samples deep on its publishers'
        hosts, keeping samples whose seq is a multiple of `divisor`, none older than `span`
        seconds before the newest (0: no limit).  Refused (LnLimitError) if a daemon has not
        the memory for it."""
        self._do("logger_add", topic=topic, depth=depth, divisor=divisor, span=span)

    def remove_topic(self, topic: str) -> None:
        self._do("logger_remove", topic=topic)

    def enable(self, keep: bool = False) -> None:
        """Start a capture; what the logger held is cleared unless `keep`."""
        self._do("logger_enable", keep=keep)

    def disable(self) -> None:
        """Stop capturing; what was captured stays until the next enable."""
        self._do("logger_disable")

    def status(self) -> dict[str, Any]:
        """Patterns, and per topic and host: depth, received/stored/missed/skipped/dropped."""
        return self._do("logger_status")

    def download_raw(self) -> dict[str, dict[str, Any]]:
        """topic -> {md_name, layout_hash, message_size, samples: [(seq, time_ns, bytes)],
        hosts, received, missed, skipped, dropped, divisor}, merged in publish order."""
        return logger_files.download(self._do)

    def download(self) -> dict[str, np.ndarray]:
        """Per topic a numpy structured array: `seq`, `publish_time` (ns) and the md's
        fields, in publish order.  `describe()` after it says what was lost."""
        self._last = self.download_raw()
        return {topic: logger_files.to_array(e) for topic, e in self._last.items()}

    def describe(self) -> dict[str, Any]:
        """Counters and gaps of the last download, per topic."""
        return logger_files.describe(getattr(self, "_last", {}))

    def save(self, path: str | Path, encoding: str | None = None) -> dict[str, Any]:
        """Download and write to `path` on this host: .mcap (`encoding` "ros2" (None: the
        default), "json" or "ln", docs/recording.md "Encodings") or .npz."""
        return logger_files.save(self.download_raw(), Path(path), encoding)

    def save_on_manager(self, path: str, encoding: str | None = None) -> dict[str, Any]:
        """Let the manager download and write to `path` on the manager's host."""
        return self._do("logger_save", path=path, encoding=encoding)

    def remove(self) -> None:
        """Remove the logger and its samples from the manager and every daemon."""
        self._do("logger_remove")
