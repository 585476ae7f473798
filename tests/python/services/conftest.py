"""Fixtures of the service tests: the private manager of the topic tests (unique instance,
free port, log in a file), the C service_tool started against it, and a thread that
handles a client's service requests with wait_and_handle_service_group_requests."""

from __future__ import annotations

import json
import subprocess
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
from topics.conftest import TOOLS, Manager, manager, wait_ready  # noqa: F401 - fixture

import links_and_nodes as ln

REPO = Path(__file__).resolve().parents[3]
SERVICE_TOOL = TOOLS / "service_tool"

ln.add_message_definition_dir(REPO / "tests" / "fixtures" / "md" / "services")
ln.add_message_definition_dir(REPO / "tests" / "fixtures" / "md" / "valid")

LIMIT = 60.0  # seconds: an upper bound against hangs, never a pass criterion
GOAL = [0.1 * j - 0.3 for j in range(7)]  # a plan_path goal with inexact binary fractions


def _tool_path() -> str:
    if not SERVICE_TOOL.exists():
        pytest.fail(f"{SERVICE_TOOL} is missing: run scons first")
    return str(SERVICE_TOOL)


def start_provider(mgr: Manager, name: str, *args: str) -> subprocess.Popen[str]:
    """`service_tool provide NAME ARGS...`, once it said "ready" (stopped by the fixture)."""
    proc = subprocess.Popen([_tool_path(), "provide", name, *args], stdout=subprocess.PIPE,
                            text=True, env=mgr.env)
    mgr.tools.append(proc)
    wait_ready(proc, LIMIT)
    return proc


def c_call(mgr: Manager, name: str, *args: str) -> tuple[int, dict[str, Any]]:
    """`service_tool call NAME ARGS...`: its exit status and the JSON it printed."""
    done = subprocess.run([_tool_path(), "call", name, *args], capture_output=True,
                          text=True, env=mgr.env, timeout=LIMIT * 2)
    assert done.returncode in (0, 1), f"service_tool failed: {done.stderr}"
    return done.returncode, json.loads(done.stdout)


@contextmanager
def serving(clnt: ln.client, group: str | None = None) -> Iterator[list[int]]:
    """Handle `clnt`'s requests of `group` in a thread until the block ends; yields the
    list of what each wait_and_handle_service_group_requests returned."""
    stop = threading.Event()
    counts: list[int] = []
    errors: list[BaseException] = []

    def run() -> None:
        try:
            while not stop.is_set():
                counts.append(clnt.wait_and_handle_service_group_requests(group, timeout=0.05))
        except BaseException as exc:  # noqa: BLE001 - reported by the test
            errors.append(exc)

    thread = threading.Thread(target=run, name="serving")
    thread.start()
    try:
        yield counts
    finally:
        stop.set()
        thread.join(LIMIT)
    assert not thread.is_alive(), "the serving thread hangs"
    assert not errors, errors


# ---- robot/plan_path as service_tool answers it (the Python providers answer the same) ----
def plan(goal: list[float], max_velocity: float, constraints: list[str]) -> dict[str, Any]:
    """The response to a plan_path request: one waypoint per constraint i (see
    service_tool.c), status = their number, message = them joined by ","."""
    return {
        "waypoints": [{
            "timestamp": i * 0.5,
            "cycle": i,
            "position": [g + i for g in goal],
            "velocity": [max_velocity] * 7,
            "effort": [float(len(c.encode()) + j) for j in range(7)],
        } for i, c in enumerate(constraints)],
        "status": len(constraints),
        "message": ",".join(constraints),
    }


def plan_path_handler(request: ln.service_request) -> None:
    """A Python provider of robot/plan_path that answers like service_tool."""
    req = request.req
    constraints = [c.data for c in req.constraints]
    if "fail" in constraints:
        request.respond_error(f"constraint {constraints.index('fail')} is 'fail'")
        return
    request.respond(plan(list(req.goal), req.max_velocity, constraints))
