"""examples/rust/rust_robot.lnc: the demo robot system with its controller, a monitor and a
service caller in Rust beside the C sensor and the Python supervisor, run end to end by
ln_manager with a private instance, ports, key and runtime directory.  The Rust controller
(1 kHz on absolute deadlines) closes the loop, the Python supervisor's calls reach its
service, the Rust caller's unsafe gains are refused, the Rust monitor sees every cycle; after
`quit` every process exited by itself with status 0 and no segment is left."""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path

import pytest
from buildtree import missing_test_tool, not_under_sanitizers

from demo.test_robot_lnc import LIMIT, REPO, TRACKING, Demo, live, run_demo, wait_for_output
from links_and_nodes.manager.config import load
from links_and_nodes.manager.frontends.launch import segments
from links_and_nodes.tools.scripting import connect

pytestmark = not_under_sanitizers(
    "the Rust programs link the release libln of build/cargo-rust (cargo builds against one "
    "libln); the release run tests them")

CONFIG = REPO / "examples" / "rust" / "rust_robot.lnc"
RUST_BIN = REPO / "build" / "cargo-rust" / "release"
PROGRAMS = ("arm_controller", "arm_monitor", "set_gains")
MONITOR = re.compile(r"^arm\.state: (\d+) samples, (\d+) missed cycles, latency max \d+ us, "
                     r"torque max [\d.]+ Nm$")


@pytest.fixture
def rust_demo(tmp_path: Path) -> Iterator[Demo]:
    missing = [p for p in PROGRAMS if not (RUST_BIN / p).exists()]
    if missing:
        missing_test_tool(f"the Rust examples {missing} (scons builds them when cargo is "
                          f"installed)")
    yield from run_demo(tmp_path, CONFIG)


def test_model() -> None:
    config = load(CONFIG, env={"LN_DEMO_PORT": "23457"})
    assert list(config.processes) == ["arm/sensor", "arm/controller", "arm/monitor",
                                      "supervisor", "probe"]
    controller = config.processes["arm/controller"]
    assert controller.command.split()[0] == str(RUST_BIN / "arm_controller")
    assert controller.ready_on_service == "arm.set_gains"
    assert config.processes["probe"].depends_on == ["supervisor"]


def test_rust_robot_lnc_end_to_end(rust_demo: Demo) -> None:
    demo = rust_demo
    demo.start()
    line = demo.stdout_line()
    assert f"listening on 127.0.0.1:{demo.manager_port}" in line, f"{line!r}\n{demo.log()}"
    line = demo.stdout_line()
    assert line.strip() == "ln_manager: all 5 processes ready", f"{line!r}\n{demo.log()}"

    with connect(f"127.0.0.1:{demo.manager_port}", timeout=LIMIT) as mgr:
        status = {p["name"]: p for p in mgr.status()}
        running = [n for n in status if n != "probe"]
        assert {n: status[n]["state"] for n in running} == dict.fromkeys(running, "ready")
        pids = [int(status[n]["pid"]) for n in running]
        services = {s["name"]: s for s in mgr.services()}
        assert services["arm.set_gains"]["provider"] == "arm.controller"
        topics = {t["name"]: t for t in mgr.topics()}
        # the Rust controller, the Python supervisor and the Rust monitor read the state
        assert topics["arm.state"]["subscribers"] == 3
        assert topics["arm.command"]["publishers"] == 1

        # Python calls the Rust service: accepted, refused with the reason, then stiffer.
        lines = wait_for_output(mgr, "supervisor", re.compile(r"tracking error .* 'stiff'"))
        assert lines[0] == "arm.set_gains 'soft': accepted"
        assert any(TRACKING.match(line) for line in lines), lines
        assert ("arm.set_gains 'unsafe': refused (kp[0] = 5000 Nm/rad is outside (0, 1000])"
                in lines)
        # The Rust caller got the Rust provider's refusal and ended by itself.
        probe = mgr.output("probe", 100)
        assert ("arm.set_gains 'unsafe': refused (kp[0] = 5000 Nm/rad is outside (0, 1000])"
                in probe), probe
        assert mgr.history("probe")[-1]["state"] == "finished"
        controller = mgr.output("arm/controller", 1000)
        assert "gains 'stiff' accepted" in controller
        assert any(re.match(r"cycle \d+: \d+ cycles in the last second", x)
                   for x in controller), controller
        # The Rust monitor follows the C sensor's samples (queued: it counts the cycles).
        lines = wait_for_output(mgr, "arm/monitor", MONITOR)
        counts = [int(m.group(1)) for x in lines if (m := MONITOR.match(x))]
        assert max(counts) > 0, lines
        # The C sensor integrates the Rust controller's torque commands.
        sensor = mgr.output("arm/sensor", 1000)
        assert any(re.match(r"t=\d+ s, cycle \d+: [1-9]\d* commands in the last second", x)
                   for x in sensor), sensor
        mgr.quit()
    assert demo.proc is not None
    assert demo.proc.wait(timeout=LIMIT) == 0, demo.log()
    assert not [pid for pid in pids if live(pid)]
    assert segments(demo.instance) == []
    log = demo.log()
    for name in ("arm/sensor", "arm/controller", "arm/monitor", "supervisor"):
        assert re.search(rf"process {re.escape(name)}: stopped \(.*exit status 0\)", log), log
