"""The settings of `ln_lsp`, as `ln_manager check` takes them on its command line: `-D`
defines, `--strict`, `--shell-timeout`, plus the md directories message definitions are
looked up in.  Read from the client's initializationOptions or its `ln` settings."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

# Shorter than ln_manager check's 10 s: a hanging command holds back the diagnostics of
# the file that runs it, never the server (reading.py runs off the server's loop).
SHELL_TIMEOUT = 2.0


@dataclass
class Settings:
    defines: dict[str, str] = field(default_factory=dict)
    strict: bool = False
    shell_timeout: float = SHELL_TIMEOUT
    md_dirs: list[Path] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)  # bad entries, shown to the user

    @classmethod
    def from_json(cls, data: Any) -> Settings:
        """Settings from `{"defines": {"A": "1"} or ["A=1"], "strict": true,
        "shellTimeout": 2, "mdDirs": ["..."]}` (also nested under "ln"); unknown keys
        are ignored, bad values are listed in `problems` and left at their default."""
        out = cls()
        if not isinstance(data, dict):
            return out
        data = data.get("ln", data) if isinstance(data.get("ln"), dict) else data
        out.defines = _defines(data.get("defines", {}), out.problems)
        strict = data.get("strict", False)
        out.strict = strict if isinstance(strict, bool) else False
        timeout = data.get("shellTimeout", SHELL_TIMEOUT)
        if isinstance(timeout, (int, float)) and 0 < timeout <= 3600:
            out.shell_timeout = float(timeout)
        else:
            out.problems.append(f"shellTimeout must be more than 0 and at most 3600 "
                                f"seconds, not {timeout!r}")
        dirs = data.get("mdDirs", [])
        out.md_dirs = [Path(d) for d in dirs if isinstance(d, str)] if isinstance(dirs, list) \
            else []
        return out


def _defines(value: Any, problems: list[str]) -> dict[str, str]:
    """`{"A": "1"}` or `["A=1"]` (as `-D A=1`)."""
    if isinstance(value, dict):
        return {str(k): str(v) for k, v in value.items()}
    out: dict[str, str] = {}
    for item in value if isinstance(value, list) else []:
        name, eq, text = str(item).partition("=")
        if not eq or not name:
            problems.append(f"define {item!r}: expected NAME=VALUE")
            continue
        out[name] = text
    return out
