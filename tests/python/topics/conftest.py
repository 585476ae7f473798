"""Fixtures of the end-to-end topic tests: a private ln_manager per test (unique instance,
free port, own runtime dir), the C/C++ tools built by SCons, and a check that no shared
memory segment of the instance outlives the test."""

from __future__ import annotations

import os
import selectors
import subprocess
import uuid
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from buildtree import build_dir

import links_and_nodes as ln
from links_and_nodes.manager.frontends import launch
from links_and_nodes.manager.frontends.launch import ManagerProcess, segments

REPO = Path(__file__).resolve().parents[3]
TOOLS = build_dir() / "tests" / "c" / "tools"
TOPIC_MDS = REPO / "tests" / "fixtures" / "md" / "topics"

ln.add_message_definition_dir(TOPIC_MDS)


@dataclass
class Manager:
    """A test's manager and the tools it started against it."""

    process: ManagerProcess
    tools: list[subprocess.Popen[str]] = field(default_factory=list)

    @property
    def instance(self) -> str:
        return self.process.instance

    @property
    def address(self) -> str:
        return self.process.address

    @property
    def proc(self) -> subprocess.Popen[bytes]:
        return self.process.proc

    @property
    def env(self) -> dict[str, str]:
        return self.process.env

    def tool(self, *args: str, cpp: bool = False) -> subprocess.Popen[str]:
        exe = TOOLS / ("topic_tool_cpp" if cpp else "topic_tool")
        if not exe.exists():
            pytest.fail(f"{exe} is missing: run scons first")
        proc = subprocess.Popen([str(exe), *args], stdout=subprocess.PIPE, text=True,
                                env=self.env)
        self.tools.append(proc)
        return proc

    def client(self, name: str = "test") -> ln.client:
        return ln.client(name, self.address)


def start_manager(instance: str, runtime: Path, *args: str) -> Manager:
    log = runtime.parent / f"{instance}.log"
    if log.exists():  # a restarted manager: keep its predecessor's log
        log = runtime.parent / f"{instance}.{len(list(runtime.parent.glob('*.log')))}.log"
    return Manager(launch.start_manager(instance, runtime, log, *args))


def wait_ready(proc: subprocess.Popen[str], limit: float = 60.0) -> None:
    """Wait (at most `limit` s, an upper bound, not a measurement) for the tool's "ready"."""
    assert proc.stdout is not None
    with selectors.DefaultSelector() as sel:
        sel.register(proc.stdout, selectors.EVENT_READ)
        if not sel.select(timeout=limit):
            proc.kill()
            pytest.fail(f"tool did not say ready within {limit} s")
    line = proc.stdout.readline()
    assert line.strip() == "ready", f"tool did not start: {line!r}, exit {proc.poll()}"


@pytest.fixture
def manager(tmp_path: Path) -> Iterator[Manager]:
    instance = f"t{os.getpid()}x{uuid.uuid4().hex[:8]}"
    mgr = start_manager(instance, tmp_path / "runtime")
    try:
        yield mgr
    finally:
        for tool in mgr.tools:  # whatever a failed test left running
            if tool.poll() is None:
                tool.kill()
                tool.wait()
        code = mgr.process.stop()
    assert code in (0, -9)  # a clean exit, or a test that SIGKILLed it on purpose
    assert segments(instance) == []
