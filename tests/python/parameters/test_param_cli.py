"""`ln_manager param list|get|set|reset|save|load` against a running C controller: text and
--json output, exit status 0 / 1 (refused, unknown, unreachable) / 2 (usage), values typed as
JSON or in flow style, and a save/load round trip that brings back every setting."""

from __future__ import annotations

import json
from pathlib import Path

from .conftest import Lab

KP = [float(j) + 0.5 for j in range(7)]


def ok(lab: Lab, *args: str) -> str:
    done = lab.cli(*args)
    assert done.returncode == 0, (args, done.stderr)
    assert done.stderr == ""
    return done.stdout


def test_list_get_set_reset(lab: Lab) -> None:
    ctl = lab.controller()
    lines = ok(lab, "list").splitlines()
    assert lines[0].split() == ["block", "service", "parameters", "overridden", "updates"]
    assert lines[1].split()[:4] == ["param_tool.ctl", "param_tool.parameters.ctl", "6", "0"]
    table = ok(lab, "list", "ctl").splitlines()
    assert table[0].split() == ["parameter", "type", "value", "override", "range",
                                "description"]
    kp_row = next(line for line in table if line.startswith("kp "))
    assert "double[7]" in kp_row and "[0, 1000]" in kp_row
    assert "stiffness per joint (Nm/rad)" in kp_row
    assert "read-only" in next(line for line in table if line.startswith("mode "))

    out = ok(lab, "set", "ctl", "kp", json.dumps(KP), "gain", "2", "label", "hi there")
    assert out.strip().startswith("param_tool.ctl: set kp, gain, label (generation 1;")
    ctl.wait_change("label")
    assert ok(lab, "get", "ctl", "kp").strip() == json.dumps(KP)
    assert ok(lab, "get", "param_tool.ctl", "label").strip() == '"hi there"'
    text = ok(lab, "get", "ctl")
    assert "gain: 2.0  (overridden by set)" in text
    assert "mode: 3" in text
    got = json.loads(ok(lab, "get", "ctl", "gain", "--json"))
    assert got["id"] == "param_tool.ctl" and got["live"] is True
    assert [p["name"] for p in got["parameters"]] == ["gain"]
    assert got["parameters"][0]["value"] == 2.0

    # flow style values, nan for a float (outside any range)
    done = lab.cli("set", "ctl", "limits", "[nan, 0.25]")
    assert done.returncode == 1 and "NaN is below the minimum -1" in done.stderr
    ok(lab, "set", "ctl", "limits", "[-1, 0.25]")

    lines = ok(lab, "changes", "ctl").splitlines()
    assert [line.split()[0] for line in lines] == ["1", "2"]
    assert lines[0].split(None, 3)[2:] == ["set", f"kp = {json.dumps(KP)}, gain = 2.0, "
                                                   'label = "hi there"']
    out = json.loads(ok(lab, "reset", "ctl", "gain", "--json"))
    assert out == {"id": "param_tool.ctl", "generation": out["generation"], "reset": ["gain"]}
    assert ok(lab, "reset", "ctl").strip() == "param_tool.ctl: reset kp, label, limits"
    assert ok(lab, "reset", "ctl").strip() == \
        "param_tool.ctl: reset nothing (no override)"
    changes = [json.loads(line) for line in
               ok(lab, "changes", "ctl", "--since", "1", "--json").splitlines()]
    assert [(c["generation"], c["op"], c["parameters"]) for c in changes] == [
        (2, "set", ["limits"]), (3, "reset", ["gain"]), (4, "reset", ["kp", "label", "limits"])]
    assert changes[0]["values"] == {"limits": [-1.0, 0.25]}
    assert "values" not in changes[1]
    assert changes[0]["time"] <= changes[2]["time"]
    assert lab.cli("changes", "ctl", "--since", "x").returncode == 2


def test_errors_and_usage(lab: Lab) -> None:
    lab.controller()
    done = lab.cli("set", "ctl", "kp", "[666, 1, 1, 1, 1, 1, 1]")
    assert done.returncode == 1
    assert done.stderr.strip() == ("ln_manager param set: error: param_tool.ctl: kp: "
                                   "kp[0] = 666 is the devil's gain (refused)")
    done = lab.cli("get", "robot")
    assert done.returncode == 1
    assert "no parameter block 'robot' (blocks: param_tool.ctl)" in done.stderr
    done = lab.cli("set", "ctl", "gain", "[1, 2")
    assert done.returncode == 1 and "bad value" in done.stderr
    for args in (("set", "ctl", "gain"), ("frob",), ("get",), ("get", "ctl", "--wait", "x")):
        done = lab.cli(*args)
        assert done.returncode == 2, args
    env_free = lab.cli("list", "--manager", "127.0.0.1:1")
    assert env_free.returncode == 1 and "cannot reach the manager" in env_free.stderr


def test_save_and_load_bring_back_every_setting(lab: Lab, tmp_path: Path) -> None:
    ctl = lab.controller()
    ok(lab, "set", "ctl", "kp", json.dumps(KP), "gain", "3.5", "label", "tuned")
    ctl.wait_change("label")
    path = tmp_path / "params.json"
    assert ok(lab, "save", str(path)).strip() == \
        f"saved 3 parameters of 1 blocks to {path}"
    data = json.loads(path.read_text())
    assert data["format"] == "ln_parameters/1"
    # the settings: what has no input (gain, label) and what is overridden (kp); not the
    # live counter and limits, not the read-only mode
    assert data["blocks"] == {"param_tool.ctl": {"kp": KP, "gain": 3.5, "label": "tuned"}}

    ok(lab, "reset", "ctl")
    ctl.wait_change("label", 2)
    assert ok(lab, "get", "ctl", "gain").strip() == "0.5"
    assert ok(lab, "load", str(path)).strip() == \
        f"loaded 1 blocks from {path}: param_tool.ctl"
    ctl.wait_change("label", 3)
    assert json.loads(ok(lab, "get", "ctl", "kp")) == KP
    assert ok(lab, "get", "ctl", "label").strip() == '"tuned"'

    data["blocks"]["gone.block"] = {"x": 1}
    data["blocks"]["param_tool.ctl"]["gain"] = 70
    path.write_text(json.dumps(data))
    done = lab.cli("load", str(path))
    assert done.returncode == 1
    assert "no parameter block 'gone.block'" in done.stderr
    assert "gain: 70 is above the maximum 10" in done.stderr
    assert ok(lab, "get", "ctl", "gain").strip() == "3.5"  # the block took none of it
    path.write_text("{}")
    done = lab.cli("load", str(path))
    assert done.returncode == 1 and "not a parameter file" in done.stderr
