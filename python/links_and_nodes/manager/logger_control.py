"""The CONTROL commands of topic loggers (docs/logging.md, "Control commands"): argument
checks and JSON results around loggers.Loggers.  `logger_fetch` carries samples as base64
of packed (u64 seq, i64 publish time ns, message bytes) records, at most FETCH_MAX bytes of
them per answer, so an answer stays within the protocol's 1 MiB frame."""

from __future__ import annotations

import base64
import math
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

from ..logger_files import FETCH_MAX, pack_samples
from .loggers import LoggerError, Loggers, check_pattern


Handler = Callable[[dict[str, Any]], Awaitable[dict[str, Any]]]


def _int(command: dict[str, Any], key: str, default: int, lo: int, hi: int) -> int:
    value = command.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise LoggerError(f'"{key}" must be an integer from {lo} to {hi}', "EINVAL")
    return value


def _str(command: dict[str, Any], key: str, default: str | None = None) -> str:
    value = command.get(key, default)
    if not isinstance(value, str) or (default is None and not value):
        raise LoggerError(f'"{key}" must be a non-empty string', "EINVAL")
    return value


def commands(loggers: Callable[[], Loggers], save: Callable[[str, Path], Awaitable[dict]]
             ) -> dict[str, Handler]:
    """The logger ops; `loggers()` raises LoggerError where the manager has none, `save`
    writes a download to a file on the manager's host."""

    async def logger_open(c: dict[str, Any]) -> dict[str, Any]:
        return {"name": loggers().open(c.get("name")).name}

    async def logger_add(c: dict[str, Any]) -> dict[str, Any]:
        span = c.get("span", 0.0)
        if isinstance(span, float) and not math.isfinite(span):
            raise LoggerError('"span" must be a finite number of seconds', "EINVAL")
        spec = check_pattern(c.get("topic"), c.get("depth", 1000), c.get("divisor", 1), span)
        await loggers().add(c.get("name"), spec)
        return await loggers().status(c.get("name"))

    async def logger_remove(c: dict[str, Any]) -> dict[str, Any]:
        await loggers().remove(c.get("name"), _str(c, "topic", ""))
        return {}

    async def logger_enable(c: dict[str, Any]) -> dict[str, Any]:
        keep = c.get("keep", False)
        if not isinstance(keep, bool):
            raise LoggerError('"keep" must be true or false', "EINVAL")
        await loggers().enable(c.get("name"), keep)
        return {}

    async def logger_disable(c: dict[str, Any]) -> dict[str, Any]:
        await loggers().disable(c.get("name"))
        return {}

    async def logger_status(c: dict[str, Any]) -> dict[str, Any]:
        return await loggers().status(c.get("name"))

    async def logger_list(c: dict[str, Any]) -> dict[str, Any]:
        return {"loggers": loggers().listing()}

    async def logger_fetch(c: dict[str, Any]) -> dict[str, Any]:
        chunk = await loggers().fetch(c.get("name"), _str(c, "topic"), _str(c, "host"),
                                      _int(c, "after", 0, 0, (1 << 64) - 1),
                                      _int(c, "max_bytes", FETCH_MAX, 1, FETCH_MAX))
        return {"md_name": chunk.md_name, "layout_hash": f"{chunk.layout_hash:016x}",
                "message_size": chunk.message_size, "enabled": chunk.enabled,
                "received": chunk.received, "stored": chunk.stored, "missed": chunk.missed,
                "skipped": chunk.skipped, "dropped": chunk.dropped,
                "first_seq": chunk.first_seq, "last_seq": chunk.last_seq,
                "start_seq": chunk.start_seq,
                "count": len(chunk.samples),
                "samples": base64.b64encode(pack_samples(chunk.samples)).decode()}

    async def logger_save(c: dict[str, Any]) -> dict[str, Any]:
        path = Path(_str(c, "path"))
        if not path.is_absolute():
            raise LoggerError(f"save needs an absolute path on the manager's host, got "
                              f"{str(path)!r}", "EINVAL")
        return await save(c.get("name"), path)

    return {"logger_open": logger_open, "logger_add": logger_add,
            "logger_remove": logger_remove, "logger_enable": logger_enable,
            "logger_disable": logger_disable, "logger_status": logger_status,
            "logger_list": logger_list, "logger_fetch": logger_fetch,
            "logger_save": logger_save}
