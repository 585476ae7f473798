"""The demo robot system's controller (examples/robot/arm_controller.cpp, through
ln/parameters.hpp) exposes its gains as the parameters kp and kd of block "gains": their
input is what the supervisor set through arm.set_gains, an override takes over from the next
cycle (checked against the same limits), and reset gives them back to the service."""

from __future__ import annotations

import re

import pytest
from demo.test_robot_lnc import Demo, demo, wait_for_output  # noqa: F401 - fixture
from polling import wait_for

from links_and_nodes.tools.scripting import ManagerError, connect

from .conftest import LIMIT

SOFT_KP = [50.0, 50.0, 30.0, 25.0, 12.0, 8.0, 4.0]
STIFF_KP = [250.0, 250.0, 160.0, 120.0, 60.0, 40.0, 20.0]


def test_demo_gains_are_parameters(demo: Demo) -> None:  # noqa: F811 - the fixture
    demo.start()
    assert "listening on" in demo.stdout_line(), demo.log()
    assert demo.stdout_line().strip() == "ln_manager: all 3 processes ready", demo.log()
    with connect(f"127.0.0.1:{demo.manager_port}", timeout=LIMIT) as mgr:
        assert mgr.param_blocks() == ["arm.controller.gains"]
        listing = mgr.param_list("gains")
        by_name = {p["name"]: p for p in listing["parameters"]}
        assert by_name["kp"]["type"] == "double" and by_name["kp"]["count"] == 7
        assert (by_name["kp"]["min"], by_name["kp"]["max"]) == (0.0, 1000.0)
        assert (by_name["kd"]["min"], by_name["kd"]["max"]) == (0.0, 50.0)
        # the input is what the supervisor set through the service
        assert mgr.param_get("gains", "kp") in (SOFT_KP, STIFF_KP)

        with pytest.raises(ManagerError, match=r"kp\[0\]: 5000 is above the maximum 1000"):
            mgr.param_set("gains", "kp", [5000.0] + STIFF_KP[1:])
        with pytest.raises(ManagerError, match=r"kp\[3\] must be above 0 Nm/rad"):
            mgr.param_set("gains", "kp", [1.0, 1.0, 1.0, 0.0, 1.0, 1.0, 1.0])

        override = [200.0] * 7
        mgr.param_set("gains", {"kp": override, "kd": [20.0] * 7})
        wait_for_output(mgr, "arm/controller",
                        re.compile(r"^parameters: kp\[0\] 200 \(changed\), kd\[0\] 20 "
                                   r"\(changed\)$"))
        wait_for(lambda: mgr.param_get("gains", "kp") == override, "the override in use")
        wait_for_output(mgr, "arm/controller",
                        re.compile(r"gains '\w+' \(kp\[0\] 200, kd\[0\] 20\)$"))
        assert mgr.param_reset("gains") == ["kp", "kd"]
        wait_for(lambda: mgr.param_get("gains", "kp") in (SOFT_KP, STIFF_KP),
                 "the service's gains back")
        mgr.quit()
