"""How a queued topic flows into a site, and a bridge in Zenoh client mode: a burst at full
speed into a topic the receiving bridge has still to set up loses nothing there (the first
samples wait for the setup, the sender is held back); a subscriber at site b that never reads
costs the other subscriber of the topic nothing (every sample, in order; the stuck one loses
its oldest samples, counted as `forced` once the bridge waited 50 ms for it); a site b bridge
that is a Zenoh client of site a's bridge carries a queued topic and a service call."""

from __future__ import annotations

import ast

from polling import wait_for
from zenoh_sites import Site, log_text, received, start_managers, wait_log


def _stream_arrives_whole(a: Site, b: Site, topic: str, count: int) -> None:
    """A subscriber at b (1024 buffers) gets all `count` samples a publisher at a sends, in
    order."""
    sub = b.peer("sub", topic, "zbtest/sample", "--buffers", "1024")
    wait_log(sub, "^subscribed")
    a.peer("pub", topic, "zbtest/sample", "--count", str(count), "--rate", "1000",
           "--wait-subscribers", "1")
    got = wait_for(lambda: len(r := received(sub)) >= count and r,
                   f"{count} samples at site b")
    assert [counter for _, counter, _ in got] == list(range(1, count + 1)), "lost or reordered"


def test_a_burst_into_a_new_topic_loses_nothing_while_it_is_set_up(
        sites: tuple[Site, Site]) -> None:
    a, b = sites
    start_managers(a, b)
    a.bridge("--listen", a.endpoint, "--out", "zb.burst,queued=64")
    bridge_b = b.bridge("--connect", a.endpoint, "--remote", a.prefix,
                        "--in", "zb.burst,queued=64")
    sub = b.peer("sub", "zb.burst", "zbtest/sample", "--buffers", "1024")
    wait_log(sub, "^subscribed")
    count = 20000
    a.peer("pub", "zb.burst", "zbtest/sample", "--count", str(count), "--wait",
           "--wait-subscribers", "1")
    wait_for(lambda: b.stats(bridge_b)["topics"].get("in:zb.burst", {}).get("published")
             == count, f"{count} samples published at site b", timeout=120)
    stats = b.stats(bridge_b)["topics"]["in:zb.burst"]
    assert (stats["received"], stats["superseded"], stats["gaps"]) == (count, 0, 0), stats
    wait_for(lambda: len(received(sub)) >= count
             or b.stats(bridge_b)["topics"]["in:zb.burst"]["forced"] > 0,
             "the subscriber to print every sample", timeout=120)
    stats = b.stats(bridge_b)["topics"]["in:zb.burst"]
    counters = [counter for _, counter, _ in received(sub)]
    assert counters == sorted(set(counters)), "reordered or repeated at the subscriber"
    # the subscriber may have lost samples only if it stalled for 50 ms (then counted)
    assert len(counters) == count or stats["forced"] > 0, (len(counters), stats)


def test_a_stuck_subscriber_costs_the_others_nothing(sites: tuple[Site, Site]) -> None:
    a, b = sites
    start_managers(a, b)
    a.bridge("--listen", a.endpoint, "--out", "zb.q,queued=256")
    bridge_b = b.bridge("--connect", a.endpoint, "--remote", a.prefix, "--in", "zb.q,queued=256")
    stuck = b.peer("sub", "zb.q", "zbtest/sample", "--buffers", "4", "--stall")
    wait_log(stuck, "^subscribed")
    _stream_arrives_whole(a, b, "zb.q", 400)
    stats = b.stats(bridge_b)["topics"]["in:zb.q"]
    assert stats["published"] == 400
    # the stuck subscriber has 4 buffers: from the 5th sample on each one is forced past it
    assert stats["forced"] >= 400 - 4 - stats["superseded"], stats
    wait_log(bridge_b, r"topic 'zb\.q' from ln/a: a subscriber here took no sample for 0\.05 "
             r"s: it loses its oldest ones \(counted as forced\)")
    assert log_text(bridge_b).count("took no sample for") == 1, "said once, not per sample"


def test_a_bridge_in_client_mode(sites: tuple[Site, Site]) -> None:
    a, b = sites
    start_managers(a, b)
    provider = a.peer("provide", "zb.echo")
    wait_log(provider, "^providing")
    bridge_a = a.bridge("--listen", a.endpoint, "--out", "zb.c,queued=256",
                        "--service-out", "zb.echo")
    bridge_b = b.bridge("--mode", "client", "--connect", a.endpoint, "--remote", a.prefix,
                        "--in", "zb.c,queued=256", "--service-in", "zb.echo")
    assert "Zenoh client" in log_text(bridge_b)
    wait_log(bridge_a, "remote bridge ln/b is up")
    _stream_arrives_whole(a, b, "zb.c", 300)
    call = b.peer("call", "zb.echo", "client")
    assert call.wait(timeout=60) == 0
    line = wait_log(call, r"^call .*$").group(0)
    assert line.startswith("call OK "), log_text(call)
    assert ast.literal_eval(line.removeprefix("call OK "))["text"] == "CLIENT"
