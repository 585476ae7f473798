"""The well-known ports: Python's links_and_nodes.default_ports holds the numbers of
libln/src/default_ports.h (the daemon's), and reads $LN_ARBITER_PORT as the daemon does."""

from __future__ import annotations

import re

import pytest
from buildtree import REPO

from links_and_nodes import default_ports


def header_macros() -> dict[str, str]:
    text = (REPO / "libln" / "src" / "default_ports.h").read_text()
    return dict(re.findall(r"^#define (LN_[A-Z_]+) (\S+)$", text, re.M))


def test_c_header_and_python_agree() -> None:
    macros = header_macros()
    assert int(macros["LN_DEFAULT_DAEMON_PORT"]) == default_ports.DAEMON_PORT
    assert macros["LN_DAEMON_PORT_ENV"] == f'"{default_ports.DAEMON_PORT_ENV}"'
    assert int(macros["LN_DATA_PORT_OFFSET"]) == default_ports.DATA_PORT_OFFSET
    assert int(macros["LN_DEFAULT_PULL_PORT"]) == default_ports.PULL_PORT


def test_daemon_port_from_the_environment() -> None:
    assert default_ports.daemon_port({}) == default_ports.DAEMON_PORT
    assert default_ports.daemon_port({"LN_ARBITER_PORT": ""}) == default_ports.DAEMON_PORT
    assert default_ports.daemon_port({"LN_ARBITER_PORT": "60001"}) == 60001
    for bad in ("0", "65536", "x", "-5", "\u0661\u0662"):
        with pytest.raises(ValueError, match="LN_ARBITER_PORT is not a port number"):
            default_ports.daemon_port({"LN_ARBITER_PORT": bad})
