"""The crash-injection driver at CI size: 10 processes, 12 topics, 4 services on one host,
16 SIGKILLs (every kind of component at least once) with a fixed seed; no hang, no torn
sample, recovery after every kill, nothing of the instance left afterwards."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .crash_driver import KINDS, run
from .crash_node import KEY, MAGIC, check_pattern

COUNT = 16
SEED = 7


def test_a_torn_sample_is_seen() -> None:
    """The pattern check the subscribers rely on: half of one sample and half of the next,
    or a sample still empty, is never taken for a whole one."""
    a, b = np.uint64(MAGIC | 5), np.uint64(MAGIC | 6)
    whole = a ^ KEY
    assert check_pattern(whole) == int(a)
    torn = np.concatenate([(b ^ KEY)[:256], whole[256:]])
    assert check_pattern(torn) is None
    assert check_pattern(np.zeros(512, dtype=np.uint64)) is None


def test_kills_of_every_component_are_survived(tmp_path: Path) -> None:
    lines: list[str] = []
    result = run(COUNT, SEED, tmp_path, small=True, log=lines.append)
    report = "\n".join(lines)
    assert result.problems == [], report
    assert len(result.kills) == COUNT
    assert result.kinds() == set(KINDS)
    # the publishers with loans, subscribers with borrows and providers were killed inside
    # their loan, borrow or handler at least once
    assert any(k.get("mid_operation") for k in result.kills), report
    assert result.leftovers == []
    assert result.calls["ok"] > 0
