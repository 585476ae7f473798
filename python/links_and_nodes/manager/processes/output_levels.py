"""Log levels read from process output (docs/logging.md, "Levels from process output"): a
process's `log_level_regex` makes each output line it matches a log line of the manager's
log store, with the level its group `level` names and the text of its group `text` (the
whole line without one).  Also which configured process a logging client is (by pid)."""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Mapping
from typing import Any, Protocol

from ..registry.logs import level_number


class _Proc(Protocol):
    cfg: Any
    pid: int | None


@functools.lru_cache(maxsize=256)
def _compiled(regex: str) -> re.Pattern[str]:
    return re.compile(regex)


def output_level(regex: str | None, text: str) -> tuple[int, str] | None:
    """(level, text) of an output line `regex` matches (re.search), else None; a level word
    that is no level's name counts as info."""
    if not regex:
        return None
    m = _compiled(regex).search(text)
    if m is None:
        return None
    try:
        level = level_number(m.group("level") or "")
    except ValueError:
        level = 20
    said = m.groupdict().get("text")
    return level, said if said is not None else text


def process_finder(procs: Mapping[str, _Proc],
                   any_node: bool | None = None) -> Callable[[str, int], str]:
    """host, pid -> the configured process running as that pid ("" if none): on its node, or
    on any node if `any_node` (default: for a configuration with one node only, whose host
    names differ from the clients' host ids)."""
    def find(host: str, pid: int) -> str:
        if pid <= 0:
            return ""
        anywhere = any_node if any_node is not None else \
            len({p.cfg.node for p in procs.values()}) == 1
        for name, p in procs.items():
            if p.pid == pid and (p.cfg.node == host or anywhere):
                return name
        return ""
    return find
