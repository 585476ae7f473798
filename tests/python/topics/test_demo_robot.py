"""The demo robot system of scripts/demo, short: the C arm controller and the Python planner
exchange commands and every joint state through a real manager, and the planner sets the
controller's gains through its service."""

from __future__ import annotations

import subprocess
import sys

from .conftest import REPO, Manager


def test_arm_controller_and_planner(manager: Manager) -> None:
    cycles = "400"
    planner = subprocess.Popen([sys.executable, str(REPO / "examples/python/planner.py"), cycles],
                               stdout=subprocess.PIPE, text=True, env=manager.env)
    assert planner.stdout is not None
    assert "waiting for the arm controller" in planner.stdout.readline()  # subscribed
    arm = subprocess.run([str(REPO / "build/release/examples/c/arm_controller"), cycles, "500"],
                         capture_output=True, text=True, env=manager.env, timeout=120)
    assert arm.returncode == 0, arm.stderr
    assert arm.stdout.startswith(f"arm_controller: {cycles} cycles")
    out, _ = planner.communicate(timeout=120)
    assert planner.returncode == 0, out
    assert f"planner: {cycles} states, 0 overruns, 0 missing cycles" in out
    # The controller's service, answered from its control loop: one setting taken, one refused.
    assert "planner: arm.set_gains kp=30 -> ok=True" in out
    assert "kp[3]=500 -> ok=False (kp[3] = 500 is outside (0, 100])" in out
