"""UDP links of ln_relay over loopback: loss within binomial bounds and the same lost
datagrams for the same seed, duplicates and reordering seen in the counts and in what
arrives, order without faults, replies to the right client, large datagrams, one-way
faults and the bounded queue.  Senders go in batches and wait for the relay to pass each
on, so the kernel never drops a datagram and every loss is the relay's."""

from __future__ import annotations

import socket
from collections import Counter
from collections.abc import Callable

import pytest

from links_and_nodes.relay import FaultSpec, Link, Relay, RelayError

from .conftest import UdpPeer, index_of, seq, until

Peers = Callable[..., UdpPeer]


async def send_paced(relay: Relay, client: UdpPeer, sink: UdpPeer, count: int,
                     batch: int = 100) -> None:
    """Send datagrams 0..count-1 through the relay's first link to `sink`, a batch at a
    time, each batch once the relay has taken it and `sink` has what the relay sent."""
    up = relay.stats[0].upstream
    target = relay.bound[0]
    for start in range(0, count, batch):
        end = min(start + batch, count)
        for i in range(start, end):
            client.send(seq(i), target)
        await until(lambda e=end: up.units_in == e and len(sink.received) == up.units_out,
                    f"the relay to pass on datagrams up to {end}")
    await until(lambda: up.queued == 0 and len(sink.received) == up.units_out,
                "the relay's queue to empty")


async def lost_with(seed: int, udp_peers: Peers, count: int = 5000) -> tuple[set[int], int]:
    client, sink = udp_peers(), udp_peers()
    async with Relay([Link.udp("127.0.0.1:0", sink.addr)], FaultSpec(loss=0.2),
                     seed=seed) as relay:
        await send_paced(relay, client, sink, count)
        up = relay.stats[0].upstream
    indices = [index_of(d) for d in sink.received]
    assert indices == sorted(indices)  # loss alone keeps the order
    assert (up.units_in, up.units_out + up.lost) == (count, count)
    assert (up.duplicated, up.reordered, up.overflowed, up.errors) == (0, 0, 0, 0)
    return set(range(count)) - set(indices), up.lost


async def test_loss_is_binomial_and_reproducible(udp_peers: Peers) -> None:
    first, counted = await lost_with(11, udp_peers)
    assert len(first) == counted
    assert 0.17 * 5000 <= counted <= 0.23 * 5000
    again, _ = await lost_with(11, udp_peers)
    assert again == first
    other, _ = await lost_with(12, udp_peers)
    assert other != first
    assert 0.17 * 5000 <= len(other) <= 0.23 * 5000


async def test_without_faults_everything_arrives_in_order(udp_peers: Peers) -> None:
    client, sink = udp_peers(), udp_peers()
    async with Relay([Link.udp("127.0.0.1:0", sink.addr)]) as relay:
        await send_paced(relay, client, sink, 3000)
        up = relay.stats[0].upstream
    assert [index_of(d) for d in sink.received] == list(range(3000))
    assert sink.received[1234] == seq(1234)
    assert (up.units_in, up.units_out, up.lost, up.bytes_in, up.bytes_out) == \
        (3000, 3000, 0, 3000 * 16, 3000 * 16)
    assert len(sink.sources) == 1  # one client, one socket towards the target


async def test_duplicates_and_reordering_show_in_counts_and_sequence(udp_peers: Peers) -> None:
    client, sink = udp_peers(), udp_peers()
    # A long flush time: a held datagram waits for the next batch, so each one is overtaken.
    faults = FaultSpec(duplicate=0.1, reorder=0.1, reorder_flush_ms=1000)
    async with Relay([Link.udp("127.0.0.1:0", sink.addr)], faults, seed=3) as relay:
        await send_paced(relay, client, sink, 2000, batch=50)
        up = relay.stats[0].upstream
    received = [index_of(d) for d in sink.received]
    copies = Counter(received)
    assert set(copies) == set(range(2000))
    assert sum(1 for n in copies.values() if n == 2) == up.duplicated
    assert max(copies.values()) == 2
    assert len(received) == 2000 + up.duplicated == up.units_out
    assert up.duplicated is not None and 140 <= up.duplicated <= 260
    # Each reordering is one step back, by exactly one datagram (the one held back).
    steps_back = [(a, b) for a, b in zip(received, received[1:], strict=False) if b < a]
    assert all(b == a - 1 for a, b in steps_back)
    assert len(steps_back) == up.reordered
    assert up.reordered is not None and 100 <= up.reordered <= 260


async def test_jitter_delays_but_loses_nothing(udp_peers: Peers) -> None:
    client, sink = udp_peers(), udp_peers()
    faults = FaultSpec(delay_ms=3, jitter_ms=3)
    async with Relay([Link.udp("127.0.0.1:0", sink.addr)], faults, seed=1) as relay:
        await send_paced(relay, client, sink, 1000)
    assert sorted(index_of(d) for d in sink.received) == list(range(1000))


async def test_replies_reach_each_client(udp_peers: Peers) -> None:
    echo = udp_peers(echo=True)
    alice, bob = udp_peers(), udp_peers()
    async with Relay([Link.udp("127.0.0.1:0", echo.addr)], FaultSpec(delay_ms=1),
                     seed=1) as relay:
        target = relay.bound[0]
        for i in range(200):
            client = alice if i % 2 else bob
            client.send(seq(i), target)
            await until(lambda c=client, n=i // 2 + 1: len(c.received) == n,
                        f"the reply to ping {i}")
            assert client.received[-1] == seq(i)
        stats = relay.stats[0]
        assert (stats.peers, stats.active) == (2, 2)
        assert stats.downstream.units_out == 200
    assert [index_of(d) for d in alice.received] == list(range(1, 200, 2))
    assert [index_of(d) for d in bob.received] == list(range(0, 200, 2))
    assert len(echo.sources) == 2  # a socket of its own per client


async def test_large_datagrams_pass_whole(udp_peers: Peers) -> None:
    echo, client = udp_peers(echo=True), udp_peers()
    async with Relay([Link.udp("127.0.0.1:0", echo.addr)], FaultSpec(jitter_ms=1),
                     seed=1) as relay:
        for i in range(10):
            payload = seq(i, 60_000)
            client.send(payload, relay.bound[0])
            await until(lambda n=i + 1: len(client.received) == n, f"large reply {i}")
            assert client.received[-1] == payload
        assert relay.stats[0].upstream.bytes_out == 10 * 60_000


async def test_one_way_faults_spare_the_replies(udp_peers: Peers) -> None:
    echo, client = udp_peers(echo=True), udp_peers()
    faults = FaultSpec(loss=0.5, duplicate=0.2, one_way=True)
    async with Relay([Link.udp("127.0.0.1:0", echo.addr)], faults, seed=8) as relay:
        up, down = relay.stats[0].upstream, relay.stats[0].downstream
        for start in range(0, 400, 50):
            for i in range(start, start + 50):
                client.send(seq(i), relay.bound[0])
            await until(lambda e=start + 50: up.units_in == e and down.units_in ==
                        up.units_out and len(client.received) == down.units_out,
                        "the replies")
    assert up.lost > 0 and up.duplicated
    assert (down.lost, down.duplicated) == (0, 0)
    assert down.units_out == up.units_out == len(client.received)


async def test_a_full_queue_drops_and_counts(udp_peers: Peers) -> None:
    client, sink = udp_peers(), udp_peers()
    faults = FaultSpec(delay_ms=600_000, queue_limit=10 * 1000)
    async with Relay([Link.udp("127.0.0.1:0", sink.addr)], faults, seed=1) as relay:
        for i in range(25):
            client.send(seq(i, 1000), relay.bound[0])
        up = relay.stats[0].upstream
        await until(lambda: up.units_in == 25, "the relay to take all datagrams")
        assert (up.queued, up.queued_bytes, up.overflowed, up.units_out) == (10, 10_000, 15, 0)
    assert sink.received == []
    assert relay.report()["links"][0]["upstream"]["queued"] == 10  # dropped at close


def ipv6_loopback() -> bool:
    try:
        with socket.socket(socket.AF_INET6, socket.SOCK_DGRAM) as sock:
            sock.bind(("::1", 0))
    except OSError:
        return False
    return True


@pytest.mark.skipif(not ipv6_loopback(), reason="no IPv6 loopback here")
async def test_several_links_in_one_relay_and_ipv6(udp_peers: Peers) -> None:
    client, first, second = udp_peers(), udp_peers(), udp_peers()
    async with Relay([Link.udp("127.0.0.1:0", first.addr),
                      Link.udp("[::1]:0", second.addr)]) as relay:
        (host_a, port_a), (host_b, port_b) = relay.bound
        assert (host_a, host_b) == ("127.0.0.1", "::1")
        client.send(b"a", (host_a, port_a))
        await until(lambda: first.received == [b"a"], "the first link")
        with socket.socket(socket.AF_INET6, socket.SOCK_DGRAM) as sock6:
            sock6.sendto(b"b", (host_b, port_b))
            await until(lambda: second.received == [b"b"], "the second link")
        assert relay.report()["links"][1]["listen"] == f"[::1]:{port_b}"


async def test_an_idle_client_gets_a_new_socket(udp_peers: Peers) -> None:
    echo, client = udp_peers(echo=True), udp_peers()
    async with Relay([Link.udp("127.0.0.1:0", echo.addr)], udp_idle_s=0.05) as relay:
        stats = relay.stats[0]
        client.send(b"one", relay.bound[0])
        await until(lambda: client.received == [b"one"], "the first reply")
        await until(lambda: stats.active == 0, "the idle client to be forgotten")
        client.send(b"two", relay.bound[0])
        await until(lambda: client.received == [b"one", b"two"], "the second reply")
        assert (stats.peers, stats.active) == (2, 1)
    assert len(echo.sources) == 2


async def test_relay_misuse_is_refused() -> None:
    with pytest.raises(ValueError, match="at least one link"):
        Relay([])
    with pytest.raises(ValueError, match="proto must be 'udp' or 'tcp'"):
        Link("sctp", "127.0.0.1:0", "127.0.0.1:9")  # type: ignore[arg-type]
    relay = Relay([Link.udp("127.0.0.1:0", ("127.0.0.1", 9))])
    with pytest.raises(RuntimeError, match="not running"):
        _ = relay.bound
    async with relay:
        with pytest.raises(RuntimeError, match="running already"):
            await relay.start()
    # 192.0.2.1 is for documentation (RFC 5737): no host has it, so it cannot be bound.
    failing = Relay([Link.udp("127.0.0.1:0", "127.0.0.1:9"),
                     Link.tcp("192.0.2.1:0", "127.0.0.1:9")])
    with pytest.raises(RelayError, match=r"^tcp 192\.0\.2\.1:0 -> 127\.0\.0\.1:9: cannot "
                                         r"listen on 192\.0\.2\.1:0: "):
        await failing.start()
    with pytest.raises(RuntimeError, match="not running"):  # the UDP link was closed again
        _ = failing.bound
