"""examples/robot/robot_two_hosts.lnc: the demo robot split over two hosts.  It differs from
robot.lnc only in the processes' node: lines and the hosts section; run in a lab (arm on
robot_pc, supervisor on operator_pc, the manager on robot_pc), every process gets ready,
the supervisor's set_gains call crosses hosts and it reports the tracking error from
arm.state and arm.reference forwarded to its host."""

from __future__ import annotations

import difflib
import re
import sys
from pathlib import Path

from polling import wait_for

from .conftest import DAEMON_PORT, ROOT, System

SINGLE = ROOT / "examples" / "robot" / "robot.lnc"
SPLIT = ROOT / "examples" / "robot" / "robot_two_hosts.lnc"
TRACKING = re.compile(r"^t=\d+ s tracking error rms +[\d.]+ mrad")


def _body(path: Path) -> list[str]:
    """The file without its leading comment block (which says what the file is)."""
    lines = path.read_text().splitlines()
    while lines and lines[0].startswith("#"):
        lines.pop(0)
    return lines


def test_split_differs_only_in_node_lines_and_hosts() -> None:
    changed = [line for line in difflib.unified_diff(_body(SINGLE), _body(SPLIT), n=0,
                                                     lineterm="")
               if line[:1] in "+-" and not line.startswith(("+++", "---"))]
    assert changed, "the split file must place processes on hosts"
    hosts_block = {"+hosts", "+robot_pc: eth0: %(env ROBOT_PC, 192.168.10.2)",
                   "+operator_pc: eth0: %(env OPERATOR_PC, 192.168.10.3)", "+"}
    others = [line for line in changed if line not in hosts_block]
    assert others and all(re.fullmatch(r"\+\s+node: (robot_pc|operator_pc)", line)
                          for line in others), others


def test_demo_runs_split_over_two_hosts(system: System) -> None:
    lab = system.lab
    robot, operator = lab["a"], lab["b"]
    system.start_daemon("a")
    system.start_daemon("b")
    env = system.env(robot)
    env.update(ROBOT_PC=robot.address, OPERATOR_PC=operator.address,
               LN_DEMO_PORT=str(DAEMON_PORT + 100), LN_PYTHON=sys.executable)
    manager = robot.popen(
        [sys.executable, "-m", "links_and_nodes.manager", "-c", str(SPLIT),
         "--start-all", "--wait-ready", "--exit-on-failure", "--no-console",
         "--instance", system.instance, "--daemon-key-file", str(lab.key_file)],
        env=env, log="manager.log")
    system.manager_proc = manager
    wait_for(lambda: "processes ready" in system.log("manager.log")
             or manager.poll() is not None, "the split demo to get ready", timeout=90)
    assert "all 3 processes ready" in system.log("manager.log"), system.log("manager.log")
    from netlab import in_netns

    from links_and_nodes.manager import connect

    address = f"{robot.address}:{DAEMON_PORT + 100}"
    system.mgr = in_netns(robot.netns, lambda: connect(address))
    status = {p["name"]: p for p in system.mgr.status()}
    assert status["supervisor"]["node"] == "operator_pc"
    assert status["arm/sensor"]["node"] == "robot_pc"
    wait_for(lambda: any(TRACKING.match(line) for line in system.mgr.output("supervisor")),
             "the supervisor on operator_pc to report the tracking error", timeout=60)
    streams = {(s["topic"], s["src"], s["dst"]) for s in system.mgr.network()["streams"]}
    assert ("arm.state", "robot_pc", "operator_pc") in streams, streams
    hosts = {h["name"]: h for h in system.mgr.hosts()}
    assert hosts["robot_pc"]["local"] and hosts["operator_pc"]["state"] == "up", hosts
