"""The one Python home of links_and_nodes' well-known ports and the variables that override
them; libln/src/default_ports.h holds the same numbers for C and C++ (a test compares the
two)."""

from __future__ import annotations

import os
from collections.abc import Mapping

DAEMON_PORT = 54376  # ln_daemon's TCP port (the LN "arbiter" port)
DAEMON_PORT_ENV = "LN_ARBITER_PORT"  # overrides DAEMON_PORT, for the daemon and the manager
DATA_PORT_OFFSET = 1  # the daemon's data port of topic forwarding: its TCP port plus this
PULL_PORT = 6363  # UDP port pull topics are served on (NDN's)
FOXGLOVE_PORT = 8765  # the Foxglove WebSocket protocol's usual port (ln_foxglove)


def daemon_port(env: Mapping[str, str] | None = None) -> int:
    """$LN_ARBITER_PORT, else DAEMON_PORT: where ln_daemon listens unless told otherwise.
    ValueError naming the variable if it is set but not a port number 1..65535."""
    text = (os.environ if env is None else env).get(DAEMON_PORT_ENV, "")
    if not text:
        return DAEMON_PORT
    if not (text.isascii() and text.isdigit() and 0 < int(text) < 65536):
        raise ValueError(f"{DAEMON_PORT_ENV} is not a port number: {text}")
    return int(text)
