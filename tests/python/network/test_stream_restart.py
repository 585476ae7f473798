"""What the manager reinstalls when a host's daemon is new (network/streams.py, host_up):
the streams it sends and receives on its side, and the receiving ends of the streams it
sends, whose UDP salts start from its clock again (docs/security.md, "Host-to-host data")."""

from __future__ import annotations

import asyncio
from typing import Any

from links_and_nodes.manager.network.streams import Forwarding, Stream

INSTALLED = ("spec",)


def _stream(src: str, dst: str, token: int) -> Stream:
    return Stream(1, "arm.state", src, dst, token, "udp", "addr", True,
                  installed_src=INSTALLED, installed_dst=INSTALLED)


def _forwarding(streams: list[Stream]) -> Forwarding:
    fwd: Any = Forwarding.__new__(Forwarding)
    fwd.streams = {(s.topic_id, s.src, s.dst): s for s in streams}
    fwd.dirty = asyncio.Event()
    return fwd


def test_a_new_sender_gets_new_receivers_too() -> None:
    a_to_b, b_to_c, c_to_a = _stream("a", "b", 1), _stream("b", "c", 2), _stream("c", "a", 3)
    fwd = _forwarding([a_to_b, b_to_c, c_to_a])
    fwd.host_up("a")
    assert (a_to_b.installed_src, a_to_b.installed_dst) == (None, None)  # a sends: both ends
    assert (c_to_a.installed_src, c_to_a.installed_dst) == (INSTALLED, None)  # a receives
    assert (b_to_c.installed_src, b_to_c.installed_dst) == (INSTALLED, INSTALLED)  # untouched
    assert fwd.dirty.is_set()
