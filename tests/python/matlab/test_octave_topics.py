"""Topics between GNU Octave (the MEX client, docs/matlab.md) and C and Python: every md
primitive, fixed arrays, char fields and nested mds round-trip exactly both ways; the C
topic_tool publishes and subscribes robot/joint_state against Octave."""

from __future__ import annotations

import subprocess
import threading

from buildtree import not_under_sanitizers

import links_and_nodes as ln
from links_and_nodes.md_loader import message_class

from .conftest import LIMIT, TOOLS, Manager, Octave, wait_ready
from .values import ALL_TYPES, plain

# the MEX file is built in the release tree only, and Octave cannot load it beside a
# libln built with ASan (the runtime would have to be preloaded into Octave)
pytestmark = not_under_sanitizers("the MEX client is built against the release libln")


def test_octave_publishes_every_type_to_python(manager: Manager, octave: Octave) -> None:
    with manager.client("py_sub") as clnt:
        sub = clnt.subscribe("m.types", "lnmatlab/all_types")
        octave("c = ln.Client('oct_pub'); p = c.publish('m.types', 'lnmatlab/all_types'); "
               "for i = 1:200, if p.subscribers() > 0, break; end; pause(0.05); end; "
               "p.write(expected_all_types());")
        sample = sub.read(timeout=10)
        assert sample is not None, "no sample from Octave"
        assert plain(sample.to_dict()) == ALL_TYPES


def test_python_publishes_every_type_to_octave(manager: Manager, octave: Octave) -> None:
    stop = threading.Event()
    with manager.client("py_pub") as clnt:
        pub = clnt.publish("m.types", "lnmatlab/all_types")
        packet = message_class("lnmatlab/all_types").from_dict(ALL_TYPES)

        def feed() -> None:
            while not stop.wait(0.02):
                pub.write(packet)

        feeder = threading.Thread(target=feed)
        feeder.start()
        try:
            done = octave("c = ln.Client('oct_sub'); s = c.subscribe('m.types', "
                          "'lnmatlab/all_types'); r = []; "
                          "for i = 1:30, r = s.read(1); if ~isempty(r), break; end; end; "
                          "check_same(r, expected_all_types()); disp(r.name);")
        finally:
            stop.set()
            feeder.join(LIMIT)
    assert done.stdout.strip() == "hello octave"


def test_c_publisher_to_octave(manager: Manager, octave: Octave) -> None:
    tool = manager.tool("pub-loop", "m.joint", "2000")
    wait_ready(tool)
    done = octave(
        "c = ln.Client('oct_joint'); s = c.subscribe('m.joint', 'robot/joint_state'); "
        "r = s.read(5); k = double(r.cycle); assert(isa(r.cycle, 'uint32')); "
        "assert(isa(r.position, 'double') && isequal(size(r.position), [1 7])); "
        "assert(isequal(r.position, k + (0:6) / 8)); "
        "assert(isequal(r.velocity, -k - (0:6) / 4)); assert(isequal(r.effort, k * (0:6))); "
        "printf('%d\\n', k);")
    assert int(done.stdout.split()[-1]) >= 1


def test_octave_publisher_to_c(manager: Manager, octave: Octave) -> None:
    tool = manager.tool("sub-joint", "m.joint", "1", "30")
    wait_ready(tool)
    octave("c = ln.Client('oct_joint'); p = c.publish('m.joint', 'robot/joint_state'); "
           "m = p.sample(); m.cycle = 42; m.timestamp = 0.5; m.position = (1:7) / 4; "
           "for i = 1:200, if p.subscribers() > 0, break; end; pause(0.05); end; p.write(m);")
    out, _ = tool.communicate(timeout=LIMIT)
    assert tool.returncode == 0, out
    fields = out.split()  # cycle, timestamp, then position, velocity, effort per joint
    assert fields[0] == "42"
    values = [float(x) for x in fields[1:]]
    assert values[0] == 0.5
    assert values[1::3] == [i / 4 for i in range(1, 8)]
    assert values[2::3] == [0.0] * 7


def test_clearing_objects_releases_ports(manager: Manager, octave: Octave) -> None:
    done = octave(
        "c = ln.Client('oct_rel'); p = c.publish('m.rel', 'robot/joint_state'); "
        "s = c.subscribe('m.rel', 'robot/joint_state', 4); "
        "svc = c.service('m.none', 'robot/set_gains'); printf('%d\\n', ln_mex('handles')); "
        "clear p s svc; printf('%d\\n', ln_mex('handles')); "
        "try, c.control(struct('op', 'topic_info', 'name', 'm.rel')); disp('kept'); "
        "catch err, disp(err.identifier); end; "
        "q = c.publish('m.rel2', 'robot/joint_state'); clear c; "
        "printf('%d\\n', ln_mex('handles')); clear q; printf('%d\\n', ln_mex('handles'));")
    # 4 handles; the client alone; the topic went with its last port; q keeps its client
    assert done.stdout.split() == ["4", "1", "ln:EREFUSED", "2", "0"]
    # the manager fixture checks that no shared memory segment of the instance is left


def test_octave_exit_with_open_ports_cleans_up(manager: Manager, octave: Octave) -> None:
    """Octave exiting with a client and ports still open: mexAtExit closes them."""
    octave("c = ln.Client('oct_exit'); p = c.publish('m.exit', 'robot/joint_state'); "
           "p.write(p.sample()); s = c.subscribe('m.exit', 'robot/joint_state'); "
           "exit(0);")
    proc = subprocess.run([str(TOOLS / "topic_tool"), "sub-joint", "m.exit", "1", "0.2"],
                          env=manager.env, capture_output=True, text=True, timeout=LIMIT)
    assert "ready" in proc.stdout
    with ln.client("probe", manager.address) as clnt:
        sub = clnt.subscribe("m.exit", "robot/joint_state")
        assert sub.publisher_count == 0
