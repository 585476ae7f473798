"""examples/python/asyncio_tool.py against the demo robot's C sensor and C++ controller on a
plain manager: it waits for the three topics' publishers, sets the gains through
arm.set_gains, counts every sample of arm.state, arm.command and arm.reference in one event
loop and ends by itself after --samples, or on SIGINT, with status 0."""

from __future__ import annotations

import re
import selectors
import signal
import subprocess
import sys
import time

import pytest
from buildtree import build_dir
from topics.conftest import REPO, Manager

BIN = build_dir() / "examples" / "robot"
TOOL = REPO / "examples" / "python" / "asyncio_tool.py"
LIMIT = 60.0  # upper bound for anything to happen, never a measurement
SUMMARY = re.compile(r"^(done|stopped by SIGINT): arm\.state (\d+) samples, arm\.command (\d+) "
                     r"samples, arm\.reference (\d+) samples$")


def spawn(manager: Manager, *args: str) -> subprocess.Popen[str]:
    proc = subprocess.Popen(list(args), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, env=manager.env)
    manager.tools.append(proc)  # killed by the fixture if the test fails
    return proc


def line_matching(proc: subprocess.Popen[str], pattern: str) -> list[str]:
    """Lines of proc's output up to the first that matches `pattern`."""
    assert proc.stdout is not None
    out: list[str] = []
    deadline = time.monotonic() + LIMIT
    with selectors.DefaultSelector() as sel:
        sel.register(proc.stdout, selectors.EVENT_READ)
        while time.monotonic() < deadline and sel.select(timeout=deadline - time.monotonic()):
            line = proc.stdout.readline()
            if not line:
                break
            out.append(line.rstrip("\n"))
            if re.search(pattern, line):
                return out
    pytest.fail(f"no line matching {pattern!r} within {LIMIT} s:\n" + "\n".join(out))


def start_robot(manager: Manager) -> list[subprocess.Popen[str]]:
    for exe in ("arm_sensor", "arm_controller"):
        if not (BIN / exe).exists():
            pytest.fail(f"{BIN / exe} is missing: run scons first")
    sensor = spawn(manager, str(BIN / "arm_sensor"))
    line_matching(sensor, "^publishing arm.state at 1000 Hz")
    controller = spawn(manager, str(BIN / "arm_controller"))
    line_matching(controller, "^following arm.state, serving arm.set_gains")
    return [sensor, controller]


def stop_all(procs: list[subprocess.Popen[str]]) -> None:
    for proc in reversed(procs):
        proc.send_signal(signal.SIGTERM)
        proc.communicate(timeout=LIMIT)
        assert proc.returncode == 0


def test_follows_three_topics_and_sets_gains(manager: Manager) -> None:
    robot = start_robot(manager)
    tool = spawn(manager, sys.executable, str(TOOL), "--profile", "stiff", "--samples", "300")
    out, _ = tool.communicate(timeout=LIMIT)
    assert tool.returncode == 0, out
    lines = out.splitlines()
    assert lines[0] == "arm.set_gains 'stiff': accepted", out
    summary = SUMMARY.match(lines[-1])
    assert summary is not None and summary[1] == "done", out
    assert all(int(count) >= 300 for count in summary.groups()[1:]), out
    stop_all(robot)


def test_ctrl_c_ends_it_cleanly(manager: Manager) -> None:
    robot = start_robot(manager)
    tool = spawn(manager, sys.executable, str(TOOL))
    line_matching(tool, r"^last second: arm\.state \d+ \(cycle \d+\)")
    tool.send_signal(signal.SIGINT)
    out, _ = tool.communicate(timeout=LIMIT)
    assert tool.returncode == 0, out
    summary = SUMMARY.match(out.splitlines()[-1])
    assert summary is not None and summary[1] == "stopped by SIGINT", out
    assert all(int(count) > 0 for count in summary.groups()[1:]), out
    stop_all(robot)
