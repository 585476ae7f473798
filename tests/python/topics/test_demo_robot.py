"""The programs of the demo robot system (examples/robot/) against a plain manager, without
the configuration and the daemon (tests/python/demo/ runs robot.lnc): the C arm sensor, the
C++ controller and the Python supervisor close the loop through topics, the supervisor sets
gains through the controller's service (one setting refused), stiffer gains shrink the
tracking error, and every program ends cleanly on SIGTERM."""

from __future__ import annotations

import re
import selectors
import signal
import subprocess
import sys
import time

import pytest
from buildtree import build_dir

from .conftest import REPO, Manager

BIN = build_dir() / "examples" / "robot"
LIMIT = 60.0  # upper bound for anything to happen, never a measurement
TRACKING = re.compile(r"^t=\d+ s tracking error rms +([\d.]+) mrad, .* gains '(\w+)'")


def spawn(manager: Manager, *args: str) -> subprocess.Popen[str]:
    proc = subprocess.Popen(list(args), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, env=manager.env)
    manager.tools.append(proc)  # killed by the fixture if the test fails
    return proc


def lines_until(proc: subprocess.Popen[str], done: re.Pattern[str]) -> list[str]:
    """Lines of proc's output up to and including the first that matches `done`."""
    assert proc.stdout is not None
    out: list[str] = []
    deadline = time.monotonic() + LIMIT
    with selectors.DefaultSelector() as sel:
        sel.register(proc.stdout, selectors.EVENT_READ)
        while time.monotonic() < deadline:
            if not sel.select(timeout=deadline - time.monotonic()):
                break
            line = proc.stdout.readline()
            if not line:
                break
            out.append(line.rstrip("\n"))
            if done.search(line):
                return out
    pytest.fail(f"no line matching {done.pattern!r} within {LIMIT} s:\n" + "\n".join(out))


def stop(proc: subprocess.Popen[str]) -> tuple[int, str]:
    proc.send_signal(signal.SIGTERM)
    rest, _ = proc.communicate(timeout=LIMIT)
    return proc.returncode, rest


def test_sensor_controller_supervisor(manager: Manager) -> None:
    for exe in ("arm_sensor", "arm_controller"):
        if not (BIN / exe).exists():
            pytest.fail(f"{BIN / exe} is missing: run scons first")
    sensor = spawn(manager, str(BIN / "arm_sensor"))
    lines_until(sensor, re.compile("^publishing arm.state at 1000 Hz"))
    controller = spawn(manager, str(BIN / "arm_controller"))
    lines_until(controller, re.compile("^following arm.state, serving arm.set_gains"))
    supervisor = spawn(manager, sys.executable, str(REPO / "examples/robot/supervisor.py"),
                       "--switch-after", "2")
    out = lines_until(supervisor, re.compile(r"tracking error .* gains 'stiff'"))
    out += lines_until(supervisor, re.compile(r"tracking error .* gains 'stiff'"))

    assert out[0] == "arm.set_gains 'soft': accepted"
    assert ("arm.set_gains 'unsafe': refused (kp[0] = 5000 Nm/rad is outside (0, 1000])"
            in out)
    assert "arm.set_gains 'stiff': accepted" in out
    errors = [(m[2], float(m[1])) for m in map(TRACKING.match, out) if m]
    soft = [e for profile, e in errors if profile == "soft"]
    stiff = [e for profile, e in errors if profile == "stiff"]
    assert soft and stiff, out
    # The last stiff second is past the transient of the switch; the loop really is closed.
    assert stiff[-1] < min(soft) / 2, out

    code, rest = stop(supervisor)
    assert code == 0, rest
    assert re.search(r"^stopped by SIGTERM; \d+ state and \d+ reference samples overrun$",
                     rest, re.M), rest
    code, rest = stop(controller)
    assert code == 0, rest
    assert re.search(r"^stopped by SIGTERM after \d+ cycles \(\d+ skipped, \d+ samples "
                     r"dropped\); "
                     r"2 gain settings accepted, 1 refused$", rest, re.M), rest
    code, rest = stop(sensor)
    assert code == 0, rest
    assert re.search(r"^stopped by SIGTERM after \d+ commands, \d+ late cycles, \d+ samples "
                     r"dropped$", rest, re.M), rest


def test_sensor_drops_samples_while_its_ring_is_locked(manager: Manager) -> None:
    """A ring locked for longer than the sensor's write timeout (here another publisher inside
    a zero-copy loan; in the demo the manager growing the ring for a new subscriber) costs
    samples, never the sensor: it keeps its rate, counts them and exits 0 on SIGTERM."""
    sensor = spawn(manager, str(BIN / "arm_sensor"))
    lines_until(sensor, re.compile("^publishing arm.state at 1000 Hz"))
    with manager.client("hog") as clnt:
        port = clnt.publish("arm.state", "robot/joint_state")
        for _ in range(2):
            with port.loan():
                time.sleep(0.05)  # 50 cycles of the sensor
        port.close()
    report = lines_until(sensor, re.compile(r"^t=\d+ s, cycle \d+: .* samples dropped"))
    assert sensor.poll() is None, report
    code, rest = stop(sensor)
    assert code == 0, rest
    dropped = re.search(r"(\d+) samples dropped$", rest, re.M)
    assert dropped is not None and int(dropped[1]) >= 10, rest
