"""The `parameters` key of a process in the `.lnc` (docs/configuration.md): one
`BLOCK.PARAM: VALUE` per line, `add parameters:` extending, templates replaying it, values in
JSON or flow style, every mistake an error at its line and column; and the JSON the process
gets in $LN_PARAMETERS."""

from __future__ import annotations

import json
import math
import textwrap
from pathlib import Path

import pytest

from links_and_nodes.manager.config import ConfigError, load
from links_and_nodes.tools.parameters.values import to_json

HEAD = "instance\nname: demo\nmanager: :54414\n"


def config(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "p.lnc"
    path.write_text(HEAD + textwrap.dedent(body).lstrip("\n"))
    return path


def test_parameters_key(tmp_path: Path) -> None:
    path = config(tmp_path, """
        process_template tuned
            parameters: gains.kd: 2
        process arm
            command: arm
            use_template: tuned
            add parameters: gains.kp: [1, 2.5, 3e2]
            add parameters: [
                gains.mode-x: -3
                limits.name: "soft # not a comment"
                limits.scale: nan
                # a comment line
                limits.raw: {"a": [true, null]}
            ]
        process other
            command: other
            parameters: a.b: 1
            parameters: a.c: 2
    """)
    cfg = load(path, env={})
    params = cfg.processes["arm"].parameters
    assert params["gains"] == {"kd": 2, "kp": [1, 2.5, 300.0], "mode-x": -3}
    assert params["limits"]["name"] == "soft # not a comment"
    assert math.isnan(params["limits"]["scale"])
    assert params["limits"]["raw"] == {"a": [True, None]}
    assert cfg.processes["other"].parameters == {"a": {"c": 2}}  # replaced, not added
    env = json.loads(to_json(params))
    assert env["limits"]["scale"] == "NaN"  # JSON has no NaN: the block reads the string
    assert env["gains"]["kp"] == [1, 2.5, 300.0]


@pytest.mark.parametrize(("line", "column", "message"), [
    ("parameters: gains 2", 17, "'parameters' takes BLOCK.PARAM: VALUE, got 'gains 2'"),
    ("parameters: gains.kp:", 17, "'parameters': no value for gains.kp"),
    ("parameters: ga.ins.kp: 1", 17, None),
    ("parameters: a b.kp: 1", 17, "'a b.kp' is no BLOCK.PARAM"),
    ("parameters: gains.kp: [1, 2", 26, "'parameters': gains.kp: bad value"),
])
def test_parameters_errors(tmp_path: Path, line: str, column: int, message: str | None
                           ) -> None:
    path = config(tmp_path, f"""
        process arm
            command: arm
            {line}
    """)
    if message is None:  # a dot in the parameter name is fine, the block has none
        assert load(path, env={}).processes["arm"].parameters == {"ga": {"ins.kp": 1}}
        return
    with pytest.raises(ConfigError) as err:
        load(path, env={})
    (problem,) = err.value.problems
    assert problem.location.line == 6 and problem.location.col == column, problem
    assert message in problem.message
