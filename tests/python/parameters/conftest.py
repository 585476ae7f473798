"""Fixtures of the parameter tests: a private manager per test (unique instance, free port, own
runtime directory; the topic tests' fixture), the C controller param_tool (a block "ctl" at
1 kHz that prints every change it takes) started against it, and the scripting API on it.
Every process a test started is stopped after it, and no segment of its instance is left."""

from __future__ import annotations

import os
import queue
import re
import subprocess
import sys
import threading
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest
from polling import wait_for
from topics.conftest import TOOLS, Manager, manager  # noqa: F401 - fixture

from links_and_nodes.tools.scripting import connect

REPO = Path(__file__).resolve().parents[3]
PARAM_TOOL = TOOLS / "param_tool"
LIMIT = 60.0  # seconds: an upper bound against hangs, never a pass criterion
CHANGE = re.compile(r"^change (\d+) (\S+) (.*)$")
PYTHONPATH = os.pathsep.join([str(REPO / "python"), str(REPO)])


@dataclass
class Change:
    update: int  # the loop's update() count
    name: str
    value: str   # as the tool prints it


@dataclass
class Controller:
    """A running param_tool: its service name and the changes it printed so far."""

    proc: subprocess.Popen[str]
    service: str
    lines: queue.Queue[str | None] = field(default_factory=queue.Queue)
    changes: list[Change] = field(default_factory=list)
    other: list[str] = field(default_factory=list)
    thread: threading.Thread | None = None

    def stop(self) -> None:
        """SIGTERM (SIGKILL after LIMIT), then the end of its output."""
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(LIMIT)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        if self.thread is not None:
            self.thread.join(LIMIT)
        assert self.proc.stdout is not None
        self.proc.stdout.close()

    def pump(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.put(line.rstrip("\n"))
        self.lines.put(None)

    def collect(self) -> list[Change]:
        """Take the lines printed so far; every change so far."""
        while True:
            try:
                line = self.lines.get_nowait()
            except queue.Empty:
                return self.changes
            if line is None:
                return self.changes
            match = CHANGE.match(line)
            if match:
                self.changes.append(Change(int(match.group(1)), match.group(2),
                                           match.group(3)))
            else:
                self.other.append(line)

    def changes_of(self, name: str) -> list[Change]:
        return [c for c in self.collect() if c.name == name]

    def wait_change(self, name: str, count: int = 1) -> list[Change]:
        """Until `count` changes of `name` were printed; those of `name`."""
        wait_for(lambda: len(self.changes_of(name)) >= count, f"{count} change(s) of {name}",
                 LIMIT)
        return self.changes_of(name)


def start_controller(env: dict[str, str], *args: str) -> Controller:
    """param_tool ARGS with `env`, once it said "ready" and named its service."""
    if not PARAM_TOOL.exists():
        pytest.fail(f"{PARAM_TOOL} is missing: run scons first")
    proc = subprocess.Popen([str(PARAM_TOOL), *args], stdout=subprocess.PIPE, text=True,
                            env=env)
    ctl = Controller(proc, "")
    ctl.thread = threading.Thread(target=ctl.pump, daemon=True, name="param_tool")
    ctl.thread.start()
    try:
        first = ctl.lines.get(timeout=LIMIT)
        second = ctl.lines.get(timeout=LIMIT)
    except queue.Empty:
        proc.kill()
        pytest.fail("param_tool did not say ready")
    if first != "ready" or second is None or not second.startswith("service "):
        proc.kill()
        pytest.fail(f"param_tool did not start: {first!r} {second!r}")
    ctl.service = second.split(" ", 1)[1]
    return ctl


@dataclass
class Lab:
    """A test's manager, its controllers and scripting connections."""

    mgr: Manager
    controllers: list[Controller] = field(default_factory=list)
    scripts: list[Any] = field(default_factory=list)

    @property
    def address(self) -> str:
        return self.mgr.address

    def controller(self, *args: str, env: dict[str, str] | None = None) -> Controller:
        ctl = start_controller({**self.mgr.env, **(env or {})}, *args)
        self.controllers.append(ctl)
        return ctl

    def script(self) -> Any:
        """A scripting connection (closed after the test)."""
        s = connect(self.address, timeout=LIMIT)
        self.scripts.append(s)
        return s

    def cli(self, *args: str) -> subprocess.CompletedProcess[str]:
        """`ln_manager param ARGS` against this manager."""
        env = {**self.mgr.env, "PYTHONPATH": PYTHONPATH}
        return subprocess.run([sys.executable, "-m", "links_and_nodes.manager", "param",
                               *args], capture_output=True, text=True, env=env,
                              timeout=LIMIT * 2)


@pytest.fixture
def lab(manager: Manager) -> Iterator[Lab]:  # noqa: F811 - the fixture above
    world = Lab(manager)
    try:
        yield world
    finally:
        for s in world.scripts:
            s.close()
        for ctl in world.controllers:
            ctl.stop()
