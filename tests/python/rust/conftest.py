"""Fixtures of the Rust cross-language tests: the Rust side (rust/links-and-nodes/examples/
interop.rs) built with cargo into build/cargo-rust, started against the private manager of the
topic tests, and the value rules that every language computes the same way."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any

import pytest
from cargo_build import RELEASE, cargo_build
from topics.conftest import Manager, manager, wait_ready  # noqa: F401 - fixture
from topics.test_topics_cross_language import expected

LIMIT = 60.0  # seconds: an upper bound against hangs, never a pass criterion


@pytest.fixture(scope="session")
def interop() -> Path:
    """The interop example, built (release, as SCons builds it; at once when up to date)."""
    cargo_build("--example", "interop")
    return RELEASE / "examples" / "interop"


def start_rust(mgr: Manager, exe: Path, *args: str) -> subprocess.Popen[str]:
    """`interop ARGS...` against `mgr`, once it said "ready" (stopped by the fixture)."""
    proc = subprocess.Popen([str(exe), *args], stdout=subprocess.PIPE, text=True, env=mgr.env)
    mgr.tools.append(proc)
    wait_ready(proc, LIMIT)
    return proc


def rust_call(mgr: Manager, exe: Path, name: str, *args: str) -> tuple[int, dict[str, Any]]:
    """`interop call NAME ARGS...`: its exit status and the JSON it printed."""
    done = subprocess.run([str(exe), "call", name, *args], capture_output=True, text=True,
                          env=mgr.env, timeout=LIMIT * 2)
    assert done.returncode in (0, 1), f"interop failed: {done.stderr}"
    return done.returncode, json.loads(done.stdout)


def joint_state(i: int) -> dict[str, object]:
    """robot/joint_state sample i (topic_tool.c and interop.rs `joint`)."""
    return expected(i)


def _pose(i: int, base: float) -> dict[str, list[float]]:
    return {"position": [base + i + k / 8.0 for k in range(3)],
            "orientation": [-i - k / 4.0 - base for k in range(4)]}


def tool_state(i: int) -> dict[str, Any]:
    """robot/tool_state sample i, nested poses and a 6x6 array (interop.rs `tool`)."""
    return {"flange": _pose(i, 0.0), "tool": _pose(i, 0.5),
            "stiffness": [i * 1000.0 + n / 3.0 for n in range(36)], "gripper_closed": i % 2}
