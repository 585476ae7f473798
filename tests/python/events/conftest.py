"""Fixtures of the event tests: the private manager of the topic tests, the C and C++ event
tools (tests/c/tools/event_tool*.c*) started against it, reading the JSON lines a C handler
prints per call, and the serving thread of the service tests (event handlers are service
providers)."""

from __future__ import annotations

import json
import queue
import subprocess
import threading
from pathlib import Path
from typing import Any

import pytest
from reconnect.conftest import Restarts, restarts  # noqa: F401 - fixture
from services.conftest import serving  # noqa: F401 - re-exported for the tests
from topics.conftest import TOOLS, Manager, manager, wait_ready  # noqa: F401 - fixture

import links_and_nodes as ln

REPO = Path(__file__).resolve().parents[3]
EVENT_TOOL = TOOLS / "event_tool"
EVENT_TOOL_CPP = TOOLS / "event_tool_cpp"
FAULT = "robot/fault_event"
LIMIT = 60.0  # seconds: an upper bound against hangs, never a pass criterion

ln.add_message_definition_dir(REPO / "tests" / "fixtures" / "md" / "events")


def _tool(path: Path) -> str:
    if not path.exists():
        pytest.fail(f"{path} is missing: run scons first")
    return str(path)


def start_handler(mgr: Manager, event: str, *args: str, cpp: bool = False
                  ) -> subprocess.Popen[str]:
    """`event_tool connect EVENT ARGS...` (or event_tool_cpp), once it said "ready"."""
    exe = _tool(EVENT_TOOL_CPP if cpp else EVENT_TOOL)
    proc = subprocess.Popen([exe, "connect", event, *args], stdout=subprocess.PIPE, text=True,
                            env=mgr.env)
    mgr.tools.append(proc)
    wait_ready(proc, LIMIT)
    lines: queue.Queue[str] = queue.Queue()
    _lines[proc.pid] = lines

    def read() -> None:  # the lines after "ready", whole, however the pipe delivers them
        assert proc.stdout is not None
        for line in proc.stdout:
            lines.put(line)
        lines.put("")

    threading.Thread(target=read, name=f"handler {proc.pid}", daemon=True).start()
    return proc


_lines: dict[int, queue.Queue[str]] = {}


def next_call(proc: subprocess.Popen[str]) -> dict[str, Any]:
    """The next call a handler started by start_handler printed (waits at most LIMIT)."""
    try:
        line = _lines[proc.pid].get(timeout=LIMIT)
    except queue.Empty:
        pytest.fail(f"handler printed no call within {LIMIT} s")
    assert line, f"handler exited (status {proc.poll()}) instead of printing a call"
    value: dict[str, Any] = json.loads(line)
    return value


def c_call(mgr: Manager, event: str, *args: str, cpp: bool = False) -> tuple[int, Any]:
    """`event_tool call EVENT ARGS...` (or event_tool_cpp): exit status and its JSON."""
    exe = _tool(EVENT_TOOL_CPP if cpp else EVENT_TOOL)
    done = subprocess.run([exe, "call", event, *args], capture_output=True, text=True,
                          env=mgr.env, timeout=LIMIT * 2)
    assert done.returncode in (0, 1), f"event tool failed: {done.stderr}"
    return done.returncode, json.loads(done.stdout)


def handlers(clnt: ln.client, event: str) -> list[str]:
    """The service names of the handlers the manager lists for `event`."""
    listed = clnt.control("events", name=event)["events"]
    return [h["service"] for e in listed for h in e["handlers"]]
