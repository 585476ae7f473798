"""Publish in one language, subscribe in another: every field arrives equal.

C and C++ sides are the tools in tests/c/tools (built by SCons); values are a function of
the sample index i, computed the same way on both sides."""

from __future__ import annotations

import subprocess
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np

from .conftest import Manager, wait_ready

N = 200


def expected(i: int) -> dict[str, object]:
    return {
        "timestamp": i * 0.001,
        "cycle": i,
        "position": [i + j / 8.0 for j in range(7)],
        "velocity": [-i - j / 4.0 for j in range(7)],
        "effort": [float(i * j) for j in range(7)],
    }


def fill(pkt: object, i: int) -> None:
    for key, value in expected(i).items():
        setattr(pkt, key, value)


def parse_c_line(line: str) -> dict[str, object]:
    parts = line.split()
    triples = [float(x) for x in parts[2:]]
    return {
        "timestamp": float(parts[1]),
        "cycle": int(parts[0]),
        "position": triples[0::3],
        "velocity": triples[1::3],
        "effort": triples[2::3],
    }


def test_python_to_python(manager: Manager) -> None:
    with manager.client("py_both") as clnt:
        sub = clnt.subscribe("robot.state", "robot/joint_state", buffers=N)
        pub = clnt.publish("robot.state", "robot/joint_state")
        for i in range(1, N + 1):
            fill(pub.packet, i)
            pub.write()
        for i in range(1, N + 1):
            pkt = sub.read(timeout=5)
            assert pkt is not None and pkt.to_dict() == expected(i)
            assert sub.info.seq == i and sub.info.overruns == 0 and sub.info.timestamp_ns > 0


def test_c_publisher_python_subscriber(manager: Manager) -> None:
    with manager.client("py_sub") as clnt:
        sub = clnt.subscribe("robot.state", "robot/joint_state", buffers=N)
        pub = manager.tool("pub-joint", "robot.state", str(N))
        assert pub.wait(timeout=60) == 0
        for i in range(1, N + 1):
            pkt = sub.read(timeout=5)
            assert pkt is not None, f"sample {i} missing"
            got = pkt.to_dict()
            assert got == expected(i)
            assert isinstance(pkt.position, np.ndarray)
        assert sub.read(timeout=0) is None
        assert sub.overruns == 0


def start_subscriber(manager: Manager, cpp: bool = False) -> subprocess.Popen[str]:
    sub = manager.tool("sub-joint", "robot.state", str(N), "10", cpp=cpp)
    wait_ready(sub)
    return sub


@contextmanager
def python_publisher(manager: Manager) -> Iterator[None]:
    """Publish samples 1..N from Python; the publisher stays connected inside the block."""
    with manager.client("py_pub") as clnt:
        pub = clnt.publish("robot.state", "robot/joint_state")
        for i in range(1, N + 1):
            fill(pub.packet, i)
            pub.write()
        yield


def received(sub: subprocess.Popen[str]) -> list[str]:
    """The subscriber's sample lines ("ready" was read by wait_ready), all N of them."""
    out, _ = sub.communicate(timeout=60)
    assert sub.returncode == 0
    lines = out.splitlines()
    assert [parse_c_line(line) for line in lines[:N]] == [expected(i) for i in range(1, N + 1)]
    return lines[N:]


def test_python_publisher_c_subscriber(manager: Manager) -> None:
    sub = start_subscriber(manager)
    with python_publisher(manager):
        assert received(sub) == []


def test_cpp_publisher_c_subscriber(manager: Manager) -> None:
    sub = start_subscriber(manager)
    pub = manager.tool("pub-joint", "robot.state", str(N), cpp=True)
    assert pub.wait(timeout=60) == 0
    assert received(sub) == []


def test_python_publisher_cpp_subscriber(manager: Manager) -> None:
    sub = start_subscriber(manager, cpp=True)
    with python_publisher(manager):  # still connected when the subscriber reports
        assert received(sub) == ["overruns 0 publishers 1"]
