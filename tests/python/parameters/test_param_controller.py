"""Parameters of a C controller at 1 kHz (tests/c/tools/param_tool.c) set through the scripting
API: a value set appears at the loop's next update exactly once and stays; a refused value
keeps the old one and the setter gets the reason; every kind of bad input is a clear error;
reset hands the value back to the program; get shows the loop's live values; initial
overrides come from $LN_PARAMETERS; two scripts setting at the same time lose nothing."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pytest
from polling import wait_for

from links_and_nodes.tools.scripting import ManagerError

from .conftest import LIMIT, PYTHONPATH, Lab

KP = [float(10 * j + 1) for j in range(7)]
INPUT_KP = [100.0 + j for j in range(7)]


def kp_text(values: list[float]) -> str:
    return "[" + ", ".join(f"{v:.17g}" for v in values) + "]"


def test_a_set_value_appears_at_the_next_update_exactly_once(lab: Lab) -> None:
    ctl = lab.controller()
    s = lab.script()
    assert s.param_blocks() == ["param_tool.ctl"]
    assert s.param_get("ctl", "kp") == INPUT_KP
    generation = s.param_set("ctl", "kp", KP)
    (change,) = ctl.wait_change("kp")
    assert change.value == kp_text(KP)
    # The loop keeps the value: a later get (after many more updates) shows it, and the
    # change was reported once only.
    before = s.param_list("ctl")["updates"]
    wait_for(lambda: s.param_list("ctl")["updates"] > before + 100, "100 more updates")
    assert s.param_get("ctl", "kp") == KP
    assert len(ctl.changes_of("kp")) == 1
    (p,) = [p for p in s.param_list("ctl")["parameters"] if p["name"] == "kp"]
    assert p["overridden"] and p["source"] == "set" and not p["pending"]
    assert p["generation"] == generation
    assert p["input"] == INPUT_KP  # the program's own value is still there


def test_several_values_change_in_one_update(lab: Lab) -> None:
    ctl = lab.controller()
    s = lab.script()
    s.param_set("ctl", {"kp": KP, "gain": 2.5, "label": "both", "limits": [-0.25, 1]})
    changes = {c.name: c for c in ctl.wait_change("limits") and ctl.collect()}
    assert set(changes) == {"kp", "gain", "label", "limits"}
    assert len({c.update for c in changes.values()}) == 1  # the same update()
    assert changes["gain"].value == "2.5"
    assert changes["label"].value == '"both"'
    values = s.param_get("ctl")
    assert values.pop("counter") > 0
    assert values == {"kp": KP, "gain": 2.5, "label": "both", "mode": 3,
                      "limits": [-0.25, 1.0]}


def test_a_refused_value_keeps_the_old_one_and_says_why(lab: Lab) -> None:
    ctl = lab.controller()
    s = lab.script()
    s.param_set("ctl", "kp", KP)
    ctl.wait_change("kp")
    with pytest.raises(ManagerError) as err:
        s.param_set("ctl", "kp", [666.0] + KP[1:])
    assert "kp[0] = 666 is the devil's gain" in str(err.value)
    assert err.value.kind == "refused"  # type: ignore[attr-defined]
    with pytest.raises(ManagerError, match="gain 7 is reserved"):
        s.param_set("ctl", {"gain": 7, "label": "not taken"})  # all or nothing
    s.param_set("ctl", "gain", 3)  # a later accepted set shows nothing else came through
    ctl.wait_change("gain")
    assert [c.name for c in ctl.collect()] == ["kp", "gain"]
    assert s.param_get("ctl", "kp") == KP
    assert s.param_get("ctl", "label") == "init"


@pytest.mark.parametrize(("block", "name", "value", "kind", "text"), [
    ("nope", "kp", 1, "", "no parameter block 'nope' (blocks: param_tool.ctl)"),
    ("ctl", "kq", 1, "not_found", 'block "ctl" has no parameter "kq"'),
    ("ctl", "gain", "fast", "type", 'gain: expected a number (double), not the string "fast"'),
    ("ctl", "gain", [1.0], "type", "gain: expected a number (double), not a list"),
    ("ctl", "counter", 1.5, "type", "counter: expected an integer (uint64_t), not 1.5"),
    ("ctl", "counter", -1, "range", "counter: -1 is out of range for uint64_t"),
    ("ctl", "gain", 10.5, "range", "gain: 10.5 is above the maximum 10 (allowed: [0, 10])"),
    ("ctl", "kp", [1.0] * 6 + [-2.0], "range", "kp[6]: -2 is below the minimum 0"),
    ("ctl", "kp", [1.0] * 8, "size", "kp: 8 values do not fit in double[7]"),
    ("ctl", "kp", [1.0] * 3, "size", "kp: expected 7 values (double[7]), got 3"),
    ("ctl", "label", "x" * 17, "size", "label: a string of 17 bytes does not fit in char[16]"),
    ("ctl", "mode", 4, "read_only", "mode is read-only"),
    ("ctl", "limits", [0.5, float("nan")], "range", "limits[1]: NaN is below the minimum -1"),
])
def test_bad_input_is_a_clear_error(lab: Lab, block: str, name: str, value: object,
                                    kind: str, text: str) -> None:
    ctl = lab.controller()
    s = lab.script()
    with pytest.raises(ManagerError) as err:
        s.param_set(block, name, value)
    assert text in str(err.value)
    assert getattr(err.value, "kind", "") == kind
    s.param_set("ctl", "gain", 1)
    ctl.wait_change("gain")
    assert [c.name for c in ctl.collect()] == ["gain"]  # the bad one changed nothing


def test_int_is_fine_for_a_float_and_a_whole_float_for_an_int(lab: Lab) -> None:
    ctl = lab.controller()
    s = lab.script()
    s.param_set("ctl", {"gain": 4, "counter": 12.0, "limits": [0, 1]})
    ctl.wait_change("limits")
    assert s.param_get("ctl", "gain") == 4.0
    assert s.param_get("ctl", "counter") == 12
    assert s.param_get("ctl", "limits") == [0.0, 1.0]


def test_reset_hands_the_value_back_to_the_program(lab: Lab) -> None:
    ctl = lab.controller()
    s = lab.script()
    s.param_set("ctl", {"kp": KP, "gain": 9, "counter": 5})
    ctl.wait_change("counter")
    assert s.param_get("ctl", "counter") == 5  # frozen while overridden
    assert sorted(s.param_reset("ctl", ["kp", "counter"])) == ["counter", "kp"]
    changes = ctl.wait_change("kp", 2)
    assert changes[-1].value == kp_text(INPUT_KP)
    assert s.param_get("ctl", "kp") == INPUT_KP
    first = s.param_get("ctl", "counter")
    wait_for(lambda: s.param_get("ctl", "counter") > first, "the counter running again")
    assert s.param_get("ctl", "gain") == 9.0
    assert s.param_reset("ctl") == ["gain"]  # every override
    ctl.wait_change("gain", 2)
    assert s.param_get("ctl", "gain") == 0.5  # the default
    assert s.param_reset("ctl") == []
    assert [(c["op"], c["parameters"]) for c in s.param_changes("ctl")] == [
        ("set", ["kp", "gain", "counter"]), ("reset", ["kp", "counter"]), ("reset", ["gain"])]
    assert [c["generation"] for c in s.param_changes("ctl", since=2)] == [3]


def test_get_shows_the_loops_live_values(lab: Lab) -> None:
    lab.controller()
    s = lab.script()
    a = s.param_list("ctl")
    b = s.param_get("ctl", "counter")
    c = s.param_get("ctl", "counter")
    assert b < c  # the loop's counter input, read at its next updates
    answer = lab.cli("get", "ctl", "--json")
    assert answer.returncode == 0, answer.stderr
    live = json.loads(answer.stdout)
    assert live["live"] is True and live["updates"] >= a["updates"]
    (counter,) = [p for p in live["parameters"] if p["name"] == "counter"]
    assert counter["value"] == counter["input"] >= c


def test_initial_overrides_from_the_environment(lab: Lab) -> None:
    params = {"ctl": {"gain": 1.25, "label": "from env", "kp": [5000] * 7, "nope": 1},
              "other": {"x": 1}}
    ctl = lab.controller(env={"LN_PARAMETERS": json.dumps(params)})
    s = lab.script()
    listing = s.param_list("ctl")
    by_name = {p["name"]: p for p in listing["parameters"]}
    assert by_name["gain"]["override"] == 1.25 and by_name["gain"]["source"] == "config"
    assert by_name["label"]["override"] == "from env"
    assert not by_name["kp"]["overridden"]
    assert any("kp[0]: 5000 is above the maximum 1000" in e for e in listing["config_errors"])
    assert any('no parameter "nope"' in e for e in listing["config_errors"])
    # visible from the first update on, which reports the change once
    changes = {c.name: c for c in ctl.wait_change("label") and ctl.collect()}
    assert set(changes) == {"gain", "label"}
    assert changes["gain"].update == changes["label"].update == 1


SETTER = textwrap.dedent("""
    import sys
    from links_and_nodes.tools.scripting import connect
    who, count = sys.argv[1], int(sys.argv[2])
    with connect() as mgr:
        for k in range(1, count + 1):
            if who == "a":
                mgr.param_set("ctl", {"gain": k / 1000, "label": f"a{k}"})
            else:
                mgr.param_set("ctl", {"kp": [float(k)] * 7, "label": f"b{k}"})
    print("done", flush=True)
""")


def test_two_scripts_setting_at_once_lose_nothing(lab: Lab) -> None:
    ctl = lab.controller()
    s = lab.script()
    count = 150
    env = {**lab.mgr.env, "PYTHONPATH": PYTHONPATH}
    procs = [subprocess.Popen([sys.executable, "-c", SETTER, who, str(count)],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              env=env) for who in ("a", "b")]
    for proc in procs:
        out, err = proc.communicate(timeout=LIMIT * 4)
        assert proc.returncode == 0 and out.strip() == "done", err
    listing = s.param_list("ctl")
    assert listing["generation"] == 2 * count  # every set was taken, none lost
    values = s.param_get("ctl")
    assert values["gain"] == count / 1000
    assert values["kp"] == [float(count)] * 7
    assert values["label"] in (f"a{count}", f"b{count}")
    # The loop saw each parameter only move forward, ending at the last value.
    wait_for(lambda: ctl.changes_of("gain")
             and float(ctl.changes_of("gain")[-1].value) == count / 1000,
             "the last gain in the loop")
    gains = [float(c.value) for c in ctl.changes_of("gain")]
    kps = [float(c.value.strip("[]").split(",")[0]) for c in ctl.changes_of("kp")]
    assert gains == sorted(gains) and len(set(gains)) == len(gains)
    assert kps == sorted(kps) and kps[-1] == count
    updates = [c.update for c in ctl.collect()]
    assert updates == sorted(updates)
