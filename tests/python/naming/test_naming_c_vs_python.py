"""libln's naming rules (naming.c, printed by tests/c/tools/print_names) and Python's
(links_and_nodes.naming) give the same names for the same instances and environments."""

from __future__ import annotations

import os
import subprocess

import pytest
from buildtree import build_dir

from links_and_nodes import naming

INSTANCES = ["lab", "lab-1_a", "a.b", "a.b/c d", "k\u00e4se", "\u20ac!", "..", "x.y.z",
             "UPPER_lower-09", "tab\there", "\U0001f916robot"]
ENVIRONMENTS = [
    {"LN_RUNTIME_DIR": "/x/given", "XDG_RUNTIME_DIR": "/run/user/7"},
    {"XDG_RUNTIME_DIR": "/run/user/7"},
    {},
]


def python_row(instance: str, env: dict[str, str]) -> list[str]:
    directory = naming.runtime_dir(instance, env)
    parent = "" if env.get("LN_RUNTIME_DIR") else str(directory.parent)
    return [naming.sanitize_instance(instance), naming.segment_prefix(instance),
            naming.segment_name(instance, 7, 2), naming.segment_name(instance, 7, 2, "h1"),
            str(directory), parent, str(naming.service_socket(directory, 42, 3))]


@pytest.mark.parametrize("env", ENVIRONMENTS, ids=["ln_runtime_dir", "xdg", "tmp"])
def test_c_and_python_name_alike(env: dict[str, str]) -> None:
    tool = build_dir() / "tests" / "c" / "tools" / "print_names"
    assert tool.exists(), f"{tool} is missing: run scons check"
    run_env = {k: v for k, v in os.environ.items()
               if k not in ("LN_RUNTIME_DIR", "XDG_RUNTIME_DIR")} | env
    out = subprocess.run([tool, *INSTANCES], env=run_env, capture_output=True, check=True,
                         timeout=30).stdout.decode()
    rows = [line.split("\t") for line in out.splitlines()]
    assert rows == [python_row(instance, env) for instance in INSTANCES]


def test_dots_and_slashes_cannot_reach_another_instance() -> None:
    assert naming.segment_prefix("a.b") == "/ln.a_b."
    assert naming.segment_name("a.b/c", 1, 1) == "/ln.a_b_c.1.1"
    assert not naming.segment_name("a.1", 1, 1).startswith(naming.segment_prefix("a"))
    assert naming.sanitize_instance(naming.sanitize_instance("k\u00e4se.x")) == "k_se_x"


def test_parse_segment_name() -> None:
    assert naming.parse_segment_name("a.b", "/ln.a_b.12.3") == (12, 3)
    assert naming.parse_segment_name("a.b", "ln.a_b.12.3") == (12, 3)
    assert naming.parse_segment_name("a.b", "/ln.a_b.12.3.h1") is None
    assert naming.parse_segment_name("a", "/ln.a_b.12.3") is None


def test_runtime_dir_sanitizes_the_instance() -> None:
    assert str(naming.runtime_dir("a.b/c", {"XDG_RUNTIME_DIR": "/run/u"})) == "/run/u/ln/a_b_c"
    assert naming.SERVICE_SOCKET_NAME.match(naming.service_socket("/d", 5, 1).name)
