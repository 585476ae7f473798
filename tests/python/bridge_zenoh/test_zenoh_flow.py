"""How a queued topic flows into a site whose subscribers do not all keep up, and a bridge in
Zenoh client mode: a subscriber at site b that never reads costs the other subscriber of the
topic nothing (every sample, in order; the stuck one loses its oldest samples, counted as
`forced` once the bridge waited 50 ms for it), and a site b bridge that is a Zenoh client of
site a's bridge carries a queued topic and a service call."""

from __future__ import annotations

import ast

from zenoh_sites import Site, log_text, received, start_managers, wait_log
from polling import wait_for


def test_a_stuck_subscriber_costs_the_others_nothing(sites: tuple[Site, Site]) -> None:
    a, b = sites
    start_managers(a, b)
    a.bridge("--listen", a.endpoint, "--out", "zb.q,queued=256")
    bridge_b = b.bridge("--connect", a.endpoint, "--remote", a.prefix, "--in", "zb.q,queued=256")
    stuck = b.peer("sub", "zb.q", "zbtest/sample", "--buffers", "4", "--stall")
    wait_log(stuck, "^subscribed")
    sub = b.peer("sub", "zb.q", "zbtest/sample", "--buffers", "1024")
    wait_log(sub, "^subscribed")
    a.peer("pub", "zb.q", "zbtest/sample", "--count", "400", "--rate", "1000",
           "--wait-subscribers", "1")
    got = wait_for(lambda: len(r := received(sub)) >= 400 and r, "400 samples at site b")
    assert [counter for _, counter, _ in got] == list(range(1, 401)), "lost or reordered"
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
    sub = b.peer("sub", "zb.c", "zbtest/sample", "--buffers", "1024")
    wait_log(sub, "^subscribed")
    a.peer("pub", "zb.c", "zbtest/sample", "--count", "300", "--rate", "1000",
           "--wait-subscribers", "1")
    got = wait_for(lambda: len(r := received(sub)) >= 300 and r, "300 samples at site b")
    assert [counter for _, counter, _ in got] == list(range(1, 301)), "lost or reordered"
    call = b.peer("call", "zb.echo", "client")
    assert call.wait(timeout=60) == 0
    line = wait_log(call, r"^call .*$").group(0)
    assert line.startswith("call OK "), log_text(call)
    assert ast.literal_eval(line.removeprefix("call OK "))["text"] == "CLIENT"
