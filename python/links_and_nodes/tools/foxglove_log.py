"""The manager's log lines as foxglove.Log messages (JSON encoding, the `jsonschema` of
Foxglove's schema), so Foxglove's Log panel shows them: what `ln_record --logs` writes and
`ln_foxglove` publishes on the `ln.log` channel.  A leaf module: nothing of ours imported."""

from __future__ import annotations

import json
from typing import Any

# the most lines one `log` answer holds (the manager keeps as many: registry/defaults.py)
LOG_LINES = 20000
TOPIC = "ln.log"
SCHEMA_NAME = "foxglove.Log"
SCHEMA_ENCODING = "jsonschema"
MESSAGE_ENCODING = "json"
# foxglove.LogLevel: UNKNOWN 0, DEBUG 1, INFO 2, WARNING 3, ERROR 4, FATAL 5
_FOXGLOVE_LEVEL = {10: 1, 20: 2, 30: 3, 40: 4, 50: 5}

SCHEMA: dict[str, Any] = {
    "title": SCHEMA_NAME,
    "description": "A log message",
    "type": "object",
    "properties": {
        "timestamp": {
            "type": "object", "title": "time", "description": "Timestamp of log message",
            "properties": {"sec": {"type": "integer", "minimum": 0},
                           "nsec": {"type": "integer", "minimum": 0, "maximum": 999999999}}},
        "level": {
            "title": "foxglove.LogLevel", "description": "Log level",
            "oneOf": [{"title": title, "const": number} for number, title in enumerate(
                ("UNKNOWN", "DEBUG", "INFO", "WARNING", "ERROR", "FATAL"))]},
        "message": {"type": "string", "description": "Log message"},
        "name": {"type": "string", "description": "Process or node name"},
        "file": {"type": "string", "description": "Filename"},
        "line": {"type": "integer", "minimum": 0, "description": "Line number in the file"},
    },
}
SCHEMA_DATA = json.dumps(SCHEMA).encode()


def foxglove_level(level: int) -> int:
    """ln's level (10..50, Python's numbers) as a foxglove.LogLevel."""
    return _FOXGLOVE_LEVEL.get(level - level % 10, 0 if level < 10 else 5)


def message(entry: dict[str, Any]) -> dict[str, Any]:
    """A foxglove.Log message of one line of the manager's `log` answer; `name` is the
    process (or client) and its host, as `ln_manager log` shows them."""
    ns = int(entry["time_ns"])
    who = entry.get("process") or entry.get("client") or ""
    return {"timestamp": {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000},
            "level": foxglove_level(int(entry["level"])), "message": entry["text"],
            "name": f"{who}@{entry['host']}" if entry.get("host") else who,
            "file": entry.get("file", ""), "line": max(0, int(entry.get("line", 0)))}


def encode(entry: dict[str, Any]) -> bytes:
    return json.dumps(message(entry), ensure_ascii=False).encode()
