"""Fixtures of the C++ waitset tests: `cpp_lab`, the test's manager (tests/python/topics'
`manager`, which the test module imports) with a starter of tests/c/tools/waitset_tool_cpp
(killed by the manager fixture if a test fails) whose output is read line by line, each wait
bounded by LIMIT."""

from __future__ import annotations

import os
import re
import selectors
import subprocess

import pytest
from topics.conftest import TOOLS, Manager

import links_and_nodes as ln

WAITSET_TOOL_CPP = TOOLS / "waitset_tool_cpp"
LIMIT = 60.0  # seconds: an upper bound against hangs, never a pass criterion


class CppTool:
    """A running waitset_tool_cpp: its stdin, and its stdout as lines."""

    def __init__(self, proc: subprocess.Popen[bytes]) -> None:
        self.proc = proc
        self.lines: list[str] = []  # everything it printed so far
        self._seen = 0  # lines handed out by next_line
        self._partial = b""

    def _read(self, limit: float) -> bool:
        """Read what the tool wrote within `limit` s; False at its end of output."""
        assert self.proc.stdout is not None
        fd = self.proc.stdout.fileno()
        with selectors.DefaultSelector() as sel:
            sel.register(fd, selectors.EVENT_READ)
            if not sel.select(timeout=limit):
                self.proc.kill()
                pytest.fail(f"waitset_tool_cpp printed nothing within {limit} s: {self.lines}")
        chunk = os.read(fd, 65536)
        *done, self._partial = (self._partial + chunk).split(b"\n")
        self.lines += [line.decode() for line in done]
        return bool(chunk)

    def next_line(self) -> str:
        while self._seen == len(self.lines):
            if not self._read(LIMIT):
                pytest.fail(f"waitset_tool_cpp ended (exit {self.proc.wait()}): {self.lines}")
        self._seen += 1
        return self.lines[self._seen - 1]

    def until(self, pattern: str) -> list[str]:
        """The lines up to and including the first that matches `pattern`."""
        out = []
        while True:
            out.append(self.next_line())
            if re.search(pattern, out[-1]):
                return out

    def send(self, line: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(line.encode() + b"\n")
        self.proc.stdin.flush()

    def finish(self) -> tuple[int, list[str]]:
        """Close its stdin and read it to its end: exit status and the lines not yet
        handed out."""
        if self.proc.stdin is not None:
            self.proc.stdin.close()
        while self._read(LIMIT):
            pass
        rest = self.lines[self._seen:]
        self._seen = len(self.lines)
        return self.proc.wait(timeout=LIMIT), rest


class CppLab:
    """The test's manager and the waitset tools started against it."""

    def __init__(self, manager: Manager) -> None:
        self.manager = manager

    def start(self, *args: str) -> CppTool:
        """`waitset_tool_cpp ARGS...`, once it said "ready"."""
        if not WAITSET_TOOL_CPP.exists():
            pytest.fail(f"{WAITSET_TOOL_CPP} is missing: run scons first")
        proc = subprocess.Popen([str(WAITSET_TOOL_CPP), *args], stdin=subprocess.PIPE,
                                stdout=subprocess.PIPE, env=self.manager.env)
        self.manager.tools.append(proc)  # type: ignore[arg-type]  # killed all the same
        tool = CppTool(proc)
        tool.until("^ready$")
        return tool

    def client(self, name: str) -> ln.client:
        return self.manager.client(name)


@pytest.fixture(name="cpp_lab")
def cpp_lab_fixture(manager: Manager) -> CppLab:
    return CppLab(manager)
