"""Bad values from GNU Octave (docs/matlab.md): wrong field names, sizes and classes, values
out of range, and a topic's other layout give an Octave error that names the field or the
topic; Octave goes on after each."""

from __future__ import annotations

from buildtree import not_under_sanitizers

from .conftest import Manager, Octave

# the MEX file is built in the release tree only, and Octave cannot load it beside a
# libln built with ASan (the runtime would have to be preloaded into Octave)
pytestmark = not_under_sanitizers("the MEX client is built against the release libln")

CASES = {
    "unknown": ("m.bogus = 1;", "sample.bogus: unknown field"),
    "missing": ("m = rmfield(m, 'cycle');", "sample.cycle: missing field"),
    "size": ("m.position = 1:6;", "sample.position: expected 7 elements (double[7]), got 6"),
    "class": ("m.position = 'abcdefg';", "sample.position: expected real numbers (double[7]), "
              "got char"),
    "struct": ("m.cycle = struct('a', 1);", "sample.cycle: expected real numbers (uint32_t), "
               "got struct"),
    "complex": ("m.timestamp = 1i;", "sample.timestamp: expected real numbers (double), "
                "got complex double"),
    "range": ("m.cycle = -1;", "sample.cycle: uint32_t cannot hold -1"),
    "fraction": ("m.cycle = 1.5;", "sample.cycle: uint32_t cannot hold 1.5"),
    "not_struct": ("m = 3;", "sample: expected a 1x1 struct"),
}

ALL_TYPES_CASES = {
    "char_long": ("t.name = repmat('x', 1, 17);", "sample.name: char[16] holds at most 16 "
                  "characters, got 17"),
    "nested_size": ("t.inner.xyz = [1 2];", "sample.inner.xyz: expected 3 elements (float[3]), "
                    "got 2"),
    "nested_unknown": ("t.points(2).extra = 1;", "sample.points(1).extra: unknown field"),
    "array_count": ("t.points(3) = t.points(1);", "sample.points: expected 2 elements "
                    "(record[2]), got 3"),
    "char_class": ("t.name = 5;", "sample.name: expected char (char[16]), got double"),
}


def _script(cases: dict[str, tuple[str, str]], var: str, port: str) -> str:
    lines = [f"{var}0 = {port}.sample();"]
    for key, (change, _) in cases.items():
        lines.append(f"{var} = {var}0; {change} try, {port}.write({var}); disp('{key}: written');"
                     f" catch err, printf('{key}: %s: %s\\n', err.identifier, err.message); "
                     "end;")
    return " ".join(lines)


def test_bad_samples_name_the_field(manager: Manager, octave: Octave) -> None:
    done = octave(
        "c = ln.Client('oct_err'); p = c.publish('m.err', 'robot/joint_state'); "
        "a = c.publish('m.all', 'lnmatlab/all_types'); "
        + _script(CASES, "m", "p") + " " + _script(ALL_TYPES_CASES, "t", "a")
        + " p.write(m0); disp('alive');")
    out = done.stdout.splitlines()
    assert out[-1] == "alive"
    got = dict(line.split(": ", 1) for line in out[:-1])
    for key, (_, message) in {**CASES, **ALL_TYPES_CASES}.items():
        identifier, text = got[key].split(": ", 1)
        assert identifier == "ln:field", got[key]
        assert text.removeprefix("ln_mex: ").startswith(message), got[key]  # Octave's prefix


def test_other_layout_is_refused(manager: Manager, octave: Octave) -> None:
    done = octave(
        "c = ln.Client('oct_layout'); p = c.publish('m.lay', 'robot/joint_state'); "
        "try, s = c.subscribe('m.lay', 'robot/command'); disp('subscribed'); "
        "catch err, printf('%s|%s\\n', err.identifier, err.message); end; "
        "try, c.subscribe('m.x', 'robot/no_such_md'); catch err, disp(err.identifier); end; "
        "try, c.publish('m.y', 'robot/set_gains'); catch err, disp(err.message); end;")
    lines = done.stdout.splitlines()
    identifier, message = lines[0].split("|", 1)
    assert identifier == "ln:ELAYOUT"
    assert "m.lay" in message
    assert lines[1] == "ln:EREFUSED"
    assert lines[2] == "md robot/set_gains is a service, not a message"
