"""A manager restart under a running controller: the overrides live in the controller, its
client registers the block's service again with the new manager, and get/set/reset work as
before, with the values set before the restart (no configuration replays anything)."""

from __future__ import annotations

import os
import uuid
from pathlib import Path

from polling import free_port, wait_for

from links_and_nodes.manager.frontends import launch
from links_and_nodes.manager.frontends.launch import segments
from links_and_nodes.tools.scripting import ManagerError, connect

from .conftest import LIMIT, start_controller

KP = [1.5] * 7


def test_a_manager_restart_keeps_values_and_overrides(tmp_path: Path) -> None:
    instance = f"pr{os.getpid()}x{uuid.uuid4().hex[:8]}"
    port = str(free_port())
    args = ("--port", port, "--adopt-window", "5")
    managers = [launch.start_manager(instance, tmp_path / "run", tmp_path / "m0.log", *args)]
    ctl = None
    try:
        ctl = start_controller(managers[0].env)
        with connect(managers[0].address, timeout=LIMIT) as s:
            generation = s.param_set("ctl", {"kp": KP, "label": "before"})
        ctl.wait_change("label")

        managers[0].proc.kill()  # SIGKILL: nothing is cleaned up, nothing said goodbye
        managers[0].proc.wait()
        managers.append(launch.start_manager(instance, tmp_path / "run", tmp_path / "m1.log",
                                              *args))

        def blocks() -> list[str]:
            try:
                with connect(managers[1].address, timeout=LIMIT) as s:
                    return s.param_blocks()
            except ManagerError:
                return []

        assert wait_for(blocks, "the block registered with the new manager") == [
            "param_tool.ctl"]
        with connect(managers[1].address, timeout=LIMIT) as s:
            listing = s.param_list("ctl")
            assert listing["generation"] == generation
            by_name = {p["name"]: p for p in listing["parameters"]}
            assert by_name["kp"]["override"] == KP and by_name["kp"]["source"] == "set"
            assert s.param_get("ctl", "label") == "before"
            s.param_set("ctl", "gain", 2)  # and it takes new ones
            ctl.wait_change("gain")
            assert s.param_get("ctl", "gain") == 2.0
            assert s.param_reset("ctl", "label") == ["label"]
            ctl.wait_change("label", 2)
            assert s.param_get("ctl", "label") == "init"
        assert [c.name for c in ctl.collect()] == ["kp", "label", "gain", "label"]
    finally:
        if ctl is not None:
            ctl.stop()
        for mgr in managers:
            mgr.stop()
    assert segments(instance) == []
