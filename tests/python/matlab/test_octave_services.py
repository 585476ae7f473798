"""Services and parameters from GNU Octave (docs/matlab.md): calls of the C service_tool with
dynamic fields (char*, records with their own dynamic fields, a dynamic array of records in
the response), and a parameter block's get/set through its service."""

from __future__ import annotations

from buildtree import not_under_sanitizers
from services.conftest import start_provider

from .conftest import Manager, Octave

# the MEX file is built in the release tree only, and Octave cannot load it beside a
# libln built with ASan (the runtime would have to be preloaded into Octave)
pytestmark = not_under_sanitizers("the MEX client is built against the release libln")


def test_call_with_dynamic_fields(manager: Manager, octave: Octave) -> None:
    start_provider(manager, "m.gains", "--md", "robot/set_gains")
    done = octave(
        "c = ln.Client('oct_call'); "
        "r = c.call('m.gains', 'robot/set_gains', struct('kp', 1:7, 'kd', 0.5 * ones(1, 7), "
        "'profile_name', 'soft'), 5); assert(isa(r.ok, 'uint8')); "
        "printf('%d|%s\\n', r.ok, r.message);")
    assert done.stdout.strip() == "1|soft: kp sum 28, kd sum 3.5"


def test_call_with_nested_dynamic_records(manager: Manager, octave: Octave) -> None:
    start_provider(manager, "m.plan")
    done = octave(
        "c = ln.Client('oct_plan'); svc = c.service('m.plan', 'robot/plan_path'); "
        "q = svc.request(); q.goal = 1:7; q.max_velocity = 2; "
        "q.constraints = struct('data', {'ab', 'xyz'}); r = svc.call(q, 5); "
        "assert(isa(r.status, 'int32')); w = r.waypoints; "
        "printf('%d|%s|%d\\n', r.status, r.message, numel(w)); "
        "printf('%.17g ', w(2).position, w(2).effort); printf('\\n'); "
        "q.constraints = struct('data', {}); r = svc.call(q, 5); "
        "printf('%d|%s|%d\\n', r.status, r.message, numel(r.waypoints));")
    lines = done.stdout.strip().splitlines()
    assert lines[0] == "2|ab,xyz|2"
    values = [float(x) for x in lines[1].split()]
    assert values == [g + 1.0 for g in range(1, 8)] + [3.0 + j for j in range(7)]
    assert lines[2] == "0||0"


def test_parameters_get_and_set(manager: Manager, octave: Octave) -> None:
    with manager.client("py_params") as clnt:
        blk = clnt.get_parameter_block("gains")
        blk.add("kp", "double", 3, default=[1.0, 2.0, 3.0], min=0, max=100)
        blk.register()
        service = blk.service_name
        done = octave(
            f"c = ln.Client('oct_param'); v = c.param_get('{service}', 'kp'); "
            "printf('%g ', v); printf('%s\\n', mat2str(size(v))); "
            f"g = c.param_set('{service}', 'kp', [4 5 6]); printf('%d\\n', g); "
            f"try, c.param_set('{service}', 'kp', [1 2]); catch err, "
            "printf('%s|%s\\n', err.identifier, err.message); end;")
    lines = done.stdout.strip().splitlines()
    assert lines[0] == "1 2 3 [1 3]"
    assert int(lines[1]) >= 1
    identifier, message = lines[2].split("|", 1)
    assert identifier == "ln:size"
    assert "kp" in message
