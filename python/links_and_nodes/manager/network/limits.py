"""How long the manager waits on the ln_daemons of its hosts, and how a failed call to one
is told.  Read as module attributes (limits.PING_TIMEOUT), so a test may shorten them."""

from __future__ import annotations

import asyncio

POLL_INTERVAL = 1.0  # seconds between pings / counter polls of one daemon
PING_TIMEOUT = 3.0  # a daemon that does not answer within this is unreachable
CONNECT_TIMEOUT = 3.0
# How long a port request waits for its client's host to be known: well below libln's
# request timeout (10 s), so that the client gets the explanation, not a timeout.
IDENTIFY_TIMEOUT = 5.0


def reason(exc: BaseException) -> str:
    """A failed daemon call as the host listing and the logs tell it."""
    if isinstance(exc, TimeoutError | asyncio.TimeoutError):
        return "no answer from its ln_daemon"
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    return str(exc) or type(exc).__name__
