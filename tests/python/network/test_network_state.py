"""The manager's rings and streams on other hosts (network.py, rings.py, core.py) against
fake daemons (fakenet.py), with the reconciler, the host monitors and client requests
interleaved step by step: rings that go and come back, gateways, publishers that come
back, daemons that were away, shutdown.  What is checked is the state the daemons are
left in, never how long anything took."""

from __future__ import annotations

from .fakenet import World


def _recv(w: World, host: str) -> list:
    return [s for s in w.daemons[host].streams.values() if not s.sending]


def _send(w: World, host: str) -> list:
    return [s for s in w.daemons[host].streams.values() if s.sending]


async def test_a_ring_made_again_on_a_host_gets_its_stream_back() -> None:
    """b's last subscriber leaves and a new one comes before the reconciler ran: b's ring
    is removed and made again, and the stream into b must write into the new one (the
    daemon's stream maps the segment it was given, not a name)."""
    w = World()
    await w.up()
    await w.publish(w.client("a"), "t")
    sub = w.client("b")
    port = await w.subscribe(sub, "t")
    await w.net.reconcile()
    (first,) = _recv(w, "b")
    assert w.daemons["b"].live(first)
    await w.close_port(sub, port)
    await w.subscribe(sub, "t")
    await w.net.reconcile()
    (stream,) = _recv(w, "b")
    assert stream.seg is w.ring_seg("b", "t"), "b's stream writes into a removed segment"


def test_a_local_ring_made_again_gets_a_new_name() -> None:
    """The manager's own host (segments.Segments, libln): the same rule as on the others."""
    import os

    from links_and_nodes.manager.segments import Segments

    segments = Segments(f"segnames{os.getpid()}")
    try:
        first = segments.create(1, "t", "m/d", 7, 8, 2)
        grown = segments.grow(1, "m/d", 7, 8, 4)
        segments.remove(1)
        again = segments.create(1, "t", "m/d", 7, 8, 2)
        assert len({first, grown, again}) == 3, (first, grown, again)
    finally:
        segments.remove_all()
