"""The manager's rings and streams on other hosts (network/, rings.py, core.py) against
fake daemons (fakenet.py), with the reconciler, the host monitors and client requests
interleaved step by step: rings that go and come back, gateways, publishers that come
back, daemons that were away, shutdown.  What is checked is the state the daemons are
left in, never how long anything took."""

from __future__ import annotations

import asyncio

import pytest

from links_and_nodes.manager.network import limits
from links_and_nodes.manager.processes import daemon_wire as dw

from .fakenet import GATEWAY, World


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


async def test_a_publisher_back_on_its_host_continues_the_sequence() -> None:
    """The publisher on a goes (b's subscriber keeps the topic) and comes back: its
    samples must be newer than those b has, else b's daemon drops them all as stale."""
    w = World()
    await w.up()
    pub = w.client("a")
    port = await w.publish(pub, "t")
    await w.subscribe(w.client("b"), "t")
    await w.net.reconcile()
    w.ring_seg("a", "t").seq = w.ring_seg("b", "t").seq = 500  # 500 samples went over
    await w.close_port(pub, port)
    await w.net.reconcile()
    assert not w.streams("t"), "no publisher, no stream"
    await w.publish(w.client("a", "pub2"), "t")
    await w.net.reconcile()
    assert w.ring_seg("a", "t").seq >= 500, "the new publisher counts from 1 again"
    (stream,) = _send(w, "a")
    assert stream.seg is w.ring_seg("a", "t")


async def test_a_gateway_keeps_its_ring_when_its_own_subscribers_leave() -> None:
    """c has a subscriber and passes the topic on to b: when c's subscriber leaves, c's
    ring must stay, the streams through c go on (TCP would lose samples otherwise)."""
    w = World(GATEWAY)
    await w.up()
    await w.publish(w.client("a"), "t")
    sub_c = w.client("c")
    port = await w.subscribe(sub_c, "t")
    await w.subscribe(w.client("b"), "t")
    await w.net.reconcile()
    assert set(w.streams("t")) == {("a", "c"), ("c", "b")}
    seg = w.ring_seg("c", "t")
    await w.close_port(sub_c, port)
    assert seg.linked, "the gateway's ring was removed under its streams"
    await w.net.reconcile()
    assert w.ring_seg("c", "t") is seg
    assert all(w.daemons[h].live(s) for h in "abc" for s in w.daemons[h].streams.values())


async def test_no_gateway_ring_outlives_its_topic() -> None:
    """The topic ends while the reconciler waits for the core to set up its gateway ring:
    the reconciler must not make the ring afterwards (nothing would remove it)."""
    w = World(GATEWAY)
    await w.up()
    pub, sub = w.client("a"), w.client("b")
    await w.publish(pub, "t")
    await w.subscribe(sub, "t")
    tid = w.topic_id("t")
    entered, release = w.daemons["b"].gate("ring_release_reader")
    leave_sub = asyncio.ensure_future(w.core.disconnect(sub))
    await entered.wait()  # the core is busy with b's subscriber
    leave_pub = asyncio.ensure_future(w.core.disconnect(pub))
    reconcile = asyncio.ensure_future(w.net.reconcile())  # waits for the core: the gateway
    for _ in range(10):
        await asyncio.sleep(0)
    release.set()
    await asyncio.gather(leave_sub, leave_pub, reconcile)
    assert "t" not in w.core.registry.topics
    await w.net.reconcile()
    for host in "abc":
        assert w.daemons[host].segments(tid) == [], f"a ring of the ended topic is left on {host}"
        assert w.daemons[host].streams == {}, f"a stream of the ended topic is left on {host}"


async def test_a_gateway_ring_on_the_managers_host_goes_with_its_streams() -> None:
    w = World(GATEWAY, local="c")
    await w.up()
    assert w.net.hosts["c"].local
    await w.publish(w.client("a"), "t")
    sub = w.client("b")
    port = await w.subscribe(sub, "t")
    await w.net.reconcile()
    assert set(w.streams("t")) == {("a", "c"), ("c", "b")}
    seg = w.ring_seg("c", "t")
    await w.close_port(sub, port)
    await w.net.reconcile()
    assert not w.streams("t")
    assert not seg.linked, "the gateway ring on the manager's host stays"


async def test_changes_made_while_a_daemon_was_away_reach_it_when_it_is_back() -> None:
    """b's daemon is unreachable (a network outage: it keeps running) while one of its
    two queued subscribers leaves, then the other: its reader slot, ring and receiving
    stream must go once b is back."""
    w = World()
    await w.up()
    await w.publish(w.client("a"), "t")
    one, two = w.client("b", "one"), w.client("b", "two")
    port_one = await w.subscribe(one, "t", buffers=4)
    port_two = await w.subscribe(two, "t", buffers=4)
    await w.net.reconcile()
    seg = w.ring_seg("b", "t")
    assert len(seg.readers) == 2
    w.daemons["b"].reachable = False
    await w.up("b")
    assert w.state("b") == "unreachable"
    await w.close_port(one, port_one)
    w.daemons["b"].reachable = True
    await w.up("b")
    assert w.state("b") == "up"
    assert len(seg.readers) == 1, "a departed subscriber still holds its reader slot"
    w.daemons["b"].reachable = False
    await w.up("b")
    await w.close_port(two, port_two)
    await w.net.reconcile()  # the stream a -> b ends while b is away
    assert not w.streams("t")
    w.daemons["b"].reachable = True
    await w.up("b")
    assert w.state("b") == "up"
    assert not seg.linked, "b's ring of the topic stays in b's /dev/shm"
    assert w.daemons["b"].streams == {}, "b's end of the ended stream stays"


async def test_a_ring_removed_while_its_daemon_is_adopted_again_stays_removed() -> None:
    """b's daemon restarted; while the manager re-adopts b's rings one by one, a topic's
    last port on b closes: that ring must not be made again by the re-adoption."""
    w = World()
    await w.up()
    await w.publish(w.client("a"), "t1")
    await w.publish(w.client("a", "a2"), "t2")
    await w.subscribe(w.client("b"), "t1")
    sub = w.client("b", "b2")
    port = await w.subscribe(sub, "t2")
    tid = w.topic_id("t2")
    w.daemons["b"].restart()
    entered, release = w.daemons["b"].gate("ring_create")
    check = asyncio.ensure_future(w.up("b"))
    await entered.wait()  # re-adopting t1's ring
    close = asyncio.ensure_future(w.close_port(sub, port))
    await asyncio.sleep(0)
    release.set()
    await asyncio.gather(check, close)
    assert w.state("b") == "up"
    assert w.daemons["b"].segments(tid) == [], "t2's ring on b was made again"


async def test_published_is_the_publishers_ring_when_asked() -> None:
    """What the watchdog measures: the sequence number of the publisher's ring now, not
    as some earlier poll saw it."""
    w = World()
    await w.up()
    await w.publish(w.client("a"), "t")
    await w.subscribe(w.client("b"), "t")
    await w.net.reconcile()
    before = await w.core.topic_published("t")
    w.ring_seg("a", "t").seq += 25
    assert await w.core.topic_published("t") == before + 25


async def test_shutdown_leaves_no_stream_or_ring_on_the_daemons() -> None:
    """The manager shuts down while the reconciler waits for a daemon in the middle of
    setting a stream up: core.shutdown, then Network.close (as ln_manager does) must leave
    no stream and no segment of the instance on any host."""
    w = World(GATEWAY)
    await w.up()
    entered, release = w.daemons["c"].gate("stream_recv")
    w.net.start()
    await w.publish(w.client("a"), "t")
    await w.subscribe(w.client("b"), "t")
    await entered.wait()
    await w.core.shutdown()
    release.set()
    await w.net.close()
    for host in "abc":
        assert w.daemons[host].streams == {}, f"a stream is left on {host}"
        assert w.daemons[host].shm == {}, f"segments are left on {host}"


def test_a_local_ring_made_again_gets_a_new_name() -> None:
    """The manager's own host (segments.Segments, libln): the same rule as on the others."""
    import os

    from links_and_nodes.manager.registry.segments import Segments

    segments = Segments(f"segnames{os.getpid()}")
    try:
        first = segments.create(1, "t", "m/d", 7, 8, 2)
        grown = segments.grow(1, "m/d", 7, 8, 4)
        segments.remove(1)
        again = segments.create(1, "t", "m/d", 7, 8, 2)
        assert len({first, grown, again}) == 3, (first, grown, again)
    finally:
        segments.remove_all()


async def test_a_daemon_silent_while_it_is_adopted_again_does_not_hold_up_clients(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """b's daemon restarted and stops answering while the manager re-adopts its rings
    (which keeps client requests out): the monitor gives up on it, and requests go on."""
    monkeypatch.setattr(limits, "PING_TIMEOUT", 0.05)
    w = World()
    await w.up()
    await w.publish(w.client("a"), "t")
    await w.subscribe(w.client("b"), "t")
    w.daemons["b"].restart()
    w.daemons["b"].gate("ring_create")  # never answered
    await asyncio.wait_for(w.up("b"), 60)  # an upper bound, not a measurement
    assert w.state("b") == "unreachable"
    await asyncio.wait_for(w.subscribe(w.client("a", "other"), "t"), 60)


async def test_a_host_lost_while_a_stream_is_set_up_holds_up_no_other_stream() -> None:
    """a goes unreachable while b's daemon sets up the receiving end of a -> b: the
    reconciler notes it for that stream and still sets up c -> b in the same round."""
    w = World()
    await w.up()
    await w.publish(w.client("a"), "t1")
    await w.subscribe(w.client("b"), "t1")
    await w.publish(w.client("c"), "t2")
    await w.subscribe(w.client("b", "b2"), "t2")
    entered, release = w.daemons["b"].gate("stream_recv")
    reconcile = asyncio.ensure_future(w.net.reconcile())
    await entered.wait()  # t1's receiving end on b
    w.daemons["a"].reachable = False
    await w.up("a")
    assert w.state("a") == "unreachable"
    release.set()
    await reconcile
    assert w.streams("t1")[("a", "b")].error
    assert [s.ring for s in _send(w, "c")] == [w.net.clients.rings_of("c").current(w.topic_id("t2"))]


async def test_a_stream_refused_by_a_daemon_is_tried_again(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """A daemon refuses to set up a stream once (nothing else changes afterwards): the
    reconciler tries it again by itself."""
    monkeypatch.setattr(limits, "POLL_INTERVAL", 0.01)
    w = World()
    await w.up()
    refused = asyncio.Event()
    real = w.daemons["b"].stream_recv

    async def refuse_once(*args: object, **kwargs: object) -> None:
        if not refused.is_set():
            refused.set()
            raise dw.DaemonError("cannot open the ring", 14)
        await real(*args, **kwargs)

    w.daemons["b"].stream_recv = refuse_once  # type: ignore[method-assign]
    w.net.start()
    try:
        await w.publish(w.client("a"), "t")
        await w.subscribe(w.client("b"), "t")
        await refused.wait()

        async def installed() -> None:
            while not _recv(w, "b"):
                await asyncio.sleep(0.01)

        await asyncio.wait_for(installed(), 60)  # an upper bound, not a measurement
    finally:
        await w.net.close()


async def test_both_ends_of_a_stream_get_the_instance_security_level() -> None:
    """The instance's `security` goes to the sending and the receiving daemon of every
    stream (authenticate when unset); a changed level installs the streams again."""
    w = World()
    await w.up()
    await w.publish(w.client("a"), "t")
    await w.subscribe(w.client("b"), "t")
    await w.net.reconcile()
    (send,), (recv,) = _send(w, "a"), _recv(w, "b")
    assert send.token == recv.token
    assert w.daemons["a"].security[send.token] == "authenticate"
    assert w.daemons["b"].security[recv.token] == "authenticate"
    w.config.instance.security = "encrypt"  # what a reload with `security: encrypt` leaves
    await w.net.reconcile()
    (send,), (recv,) = _send(w, "a"), _recv(w, "b")
    assert w.daemons["a"].security[send.token] == "encrypt"
    assert w.daemons["b"].security[recv.token] == "encrypt"
