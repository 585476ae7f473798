"""`ln_manager -c FILE` with a process whose `parameters:` give its block initial overrides:
the process starts with them in effect from its first update (and with the refusal of a bad
one listed), and the console's `param ...` commands list, get, set, reset, save and load
them; errors are `error: ...` lines and the manager goes on."""

from __future__ import annotations

import json
import os
import time
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest
from console_manager import Console, console_manager
from polling import free_daemon_port, free_port

from links_and_nodes.tools.scripting import connect

from .conftest import LIMIT, PARAM_TOOL

CONFIG = """instance
name: {instance}
manager: 127.0.0.1:{port}

process arm/ctl
    command: {tool}
    ready_regex: ^ready
    term_timeout: 5
    parameters: ctl.gain: 1.5
    add parameters: [
        ctl.label: "from lnc"
        ctl.kp: [1, 2, 3, 4, 5, 6, 7]
        ctl.limits: [5, 5]
    ]
"""


@pytest.fixture
def console(tmp_path: Path) -> Iterator[Console]:
    if not PARAM_TOOL.exists():
        pytest.fail(f"{PARAM_TOOL} is missing: run scons first")
    instance = f"pc{os.getpid()}x{uuid.uuid4().hex[:8]}"
    port, daemon_port = free_port(), free_daemon_port()
    config = tmp_path / "params.lnc"
    config.write_text(CONFIG.format(instance=instance, port=port, tool=PARAM_TOOL))
    env = {**os.environ, "LN_RUNTIME_DIR": str(tmp_path / "run"),
           "LN_DAEMON_KEY_FILE": str(tmp_path / "daemon.key"),
           "LN_ARBITER_PORT": str(daemon_port), "PYTHONUNBUFFERED": "1"}
    env.pop("LN_MANAGER", None)
    with console_manager(config, instance, port, daemon_port, env, LIMIT,
                         cwd=tmp_path) as con:
        yield con


def test_lnc_overrides_and_console_commands(console: Console, tmp_path: Path) -> None:
    console.send("start arm/ctl")
    console.expect(lambda line: line == "starting: arm/ctl", "the start")
    with connect(console.address, timeout=LIMIT) as mgr:
        mgr.wait_ready("arm/ctl", LIMIT)
        # in effect from the first update, reported there once; the lines of one update
        # may reach the manager's output buffer one by one, so wait for the last of them
        deadline = time.monotonic() + LIMIT
        while not any(line.startswith("change 1 label") for line in mgr.output("arm/ctl")):
            assert time.monotonic() < deadline, mgr.output("arm/ctl")
            time.sleep(0.05)
        output = mgr.output("arm/ctl")
        assert any(line.startswith("change 1 kp [1, 2, 3") for line in output), output
        assert "change 1 gain 1.5" in output
        assert 'change 1 label "from lnc"' in output
        assert not any(" limits " in line for line in output)

    console.send("param get arm.ctl.ctl gain")
    assert console.expect(lambda line: True, "the gain") == ["1.5"]
    console.send("param list ctl")
    lines = console.expect(lambda line: line.startswith("configuration refused"),
                           "the refused limits")
    assert any(line.startswith("gain ") and " config " in line for line in lines)
    assert lines[-1] == ("configuration refused: refused: limits[0]: 5 is above the maximum "
                         "1 (allowed: [-1, 1])")

    console.send("param set ctl gain 3 label console")
    console.expect(lambda line: line.startswith("arm.ctl.ctl: set gain, label (generation 2"),
                   "the set")
    console.send("param set ctl gain 11")
    console.expect(lambda line: line == "error: arm.ctl.ctl: gain: 11 is above the maximum "
                   "10 (allowed: [0, 10]) (range)", "the refusal")
    console.send("param get ctl label")
    console.expect(lambda line: line == '"console"', "the label")
    console.send("param save params.json")  # relative to the manager's directory
    console.expect(lambda line: line.startswith("saved 3 parameters of 1 blocks"), "the save")
    saved = json.loads((tmp_path / "params.json").read_text())["blocks"]["arm.ctl.ctl"]
    assert saved == {"kp": [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0], "gain": 3.0,
                     "label": "console"}
    console.send("param reset ctl")
    console.expect(lambda line: line == "arm.ctl.ctl: reset kp, gain, label", "the reset")
    console.send("param get ctl gain")
    console.expect(lambda line: line == "0.5", "the default gain")
    console.send("param load params.json")
    console.expect(lambda line: line.startswith("loaded 1 blocks"), "the load")
    console.send("param get ctl gain")
    console.expect(lambda line: line == "3.0", "the loaded gain")
    console.send("param frob")
    console.expect(lambda line: line.startswith("error: unknown param command 'frob'"),
                   "the usage error")
    console.send("param get nothing")
    console.expect(lambda line: line.startswith("error: no parameter block 'nothing'"),
                   "the unknown block")
    console.send("status")  # the console goes on
    console.expect(lambda line: line.startswith("arm/ctl") and "ready" in line, "the status")
    console.send("quit")
