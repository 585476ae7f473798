"""Fixtures of the client logging tests: the private manager of the topic tests (a manager
without a configuration collects log lines too), the C and C++ log tools
(tests/c/tools/log_tool*.c*) run against it, and the scripting client connected to it."""

from __future__ import annotations

import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest
from topics.conftest import TOOLS, Manager, manager  # noqa: F401 - fixture

from links_and_nodes.tools import scripting

LIMIT = 60.0  # seconds: an upper bound against hangs, never a pass criterion
LOG_TOOL = TOOLS / "log_tool"
LOG_TOOL_CPP = TOOLS / "log_tool_cpp"


def run_tool(mgr: Manager, exe: Path, *args: str) -> list[str]:
    """The lines a log tool printed; it must end with "flushed" and exit 0."""
    if not exe.exists():
        pytest.fail(f"{exe} is missing: run scons first")
    done = subprocess.run([str(exe), *args], capture_output=True, text=True, env=mgr.env,
                          timeout=LIMIT)
    lines = done.stdout.splitlines()
    assert done.returncode == 0 and lines and lines[-1] == "flushed", \
        f"{exe.name} failed ({done.returncode}): {done.stdout} {done.stderr}"
    return lines


def printed_lines(lines: list[str]) -> dict[int, int]:
    """level -> source line of the "line LEVEL N" lines a tool printed."""
    return {int(w[1]): int(w[2]) for w in (line.split() for line in lines) if w[0] == "line"}


@pytest.fixture
def scripted(manager: Manager) -> Iterator[scripting.Manager]:  # noqa: F811
    with scripting.connect(manager.address, timeout=LIMIT) as mgr:
        yield mgr
