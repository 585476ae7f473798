"""ln_zenoh against a side that goes away and against garbage: site b's bridge killed and
started again (and site a's, the one that listens), traffic resumes and both sides log the
state; malformed samples put on a bridged key by a plain Zenoh session are dropped and
counted, and the bridge and the topic go on."""

from __future__ import annotations

from polling import wait_for
from zenoh_sites import Site, log_text, received, start_managers, wait_log


def _latest(sub: object) -> int:
    got = received(sub)  # type: ignore[arg-type]
    return got[-1][1] if got else 0


def _logged(proc: object, text: str, times: int) -> None:
    """Wait until `text` is in the log `times` times (the events are logged a tick after
    they happen)."""
    wait_for(lambda: log_text(proc).count(text) >= times,  # type: ignore[arg-type]
             f"{text!r} logged {times} times")
    assert log_text(proc).count(text) == times  # type: ignore[arg-type]


def test_bridges_killed_and_restarted_resume(sites: tuple[Site, Site]) -> None:
    a, b = sites
    start_managers(a, b)
    a_args = ("--listen", a.endpoint, "--out", "zb.state")
    b_args = ("--connect", a.endpoint, "--remote", a.prefix, "--in", "zb.state")
    bridge_a = a.bridge(*a_args)
    bridge_b = b.bridge(*b_args)
    sub = b.peer("sub", "zb.state", "zbtest/sample")
    wait_log(sub, "^subscribed")
    a.peer("pub", "zb.state", "zbtest/sample", "--rate", "100", "--wait-subscribers", "1")
    wait_for(lambda: len(received(sub)) >= 20, "samples at b")

    bridge_b.kill()
    bridge_b.wait()
    wait_log(bridge_a, "remote bridge ln/b is gone")
    wait_log(bridge_a, "no remote subscriber of ln/a/topic/zb.state any more")
    seen = _latest(sub)
    bridge_b = b.bridge(*b_args)
    wait_for(lambda: _latest(sub) > seen + 50, "samples at b again after its bridge restarted")
    _logged(bridge_a, "remote bridge ln/b is up", 2)
    _logged(bridge_a, "a remote subscriber matches ln/a/topic/zb.state", 2)
    assert a.stats(bridge_a)["topics"]["out:zb.state"]["unmatched"] > 0, \
        "samples read while b was away must be counted"

    bridge_a.kill()
    bridge_a.wait()
    wait_log(bridge_b, "remote bridge ln/a is gone")
    seen = _latest(sub)
    bridge_a = a.bridge(*a_args)
    wait_for(lambda: _latest(sub) > seen + 50, "samples at b again after a's bridge restarted")
    _logged(bridge_b, "remote bridge ln/a is up", 2)
    counters = [counter for _, counter, _ in received(sub)]
    assert counters == sorted(set(counters)) and all(ok for _, _, ok in received(sub))


def test_bad_payloads_are_dropped_and_counted(sites: tuple[Site, Site]) -> None:
    a, b = sites
    start_managers(a, b)
    # --batch off: b takes a's per-topic keys, where the bad samples go (while a offers
    # batches b takes its batch keys only; malformed batches: test_zenoh_batch.py)
    a.bridge("--listen", a.endpoint, "--out", "zb.good,queued=64", "--batch", "off")
    bridge_b = b.bridge("--connect", a.endpoint, "--remote", a.prefix, "--in", "zb.*,queued=64")
    sub = b.peer("sub", "zb.good", "zbtest/sample", "--buffers", "64")
    wait_log(sub, "^subscribed")
    a.peer("pub", "zb.good", "zbtest/sample", "--rate", "50", "--wait-subscribers", "1")
    wait_for(lambda: len(received(sub)) >= 5, "good samples at b")
    for key in ("ln/a/topic/zb.good", "ln/a/topic/zb.junk"):
        raw = b.raw("bad", key, "--connect", a.endpoint)
        assert raw.wait(timeout=60) == 0, log_text(raw)
        assert "sent 8" in log_text(raw)

    def counted() -> dict[str, dict[str, int]] | None:
        topics = b.stats(bridge_b)["topics"]
        done = all(t in topics and topics[t]["received"] - topics[t]["published"] >= 8
                   for t in ("in:zb.good", "in:zb.junk"))
        return topics if done else None

    topics = wait_for(counted, "b's bridge to have handled the bad samples")
    assert isinstance(topics, dict)
    for name in ("in:zb.good", "in:zb.junk"):
        t = topics[name]
        assert (t["bad_attachment"], t["bad_size"], t["refused"]) == (5, 2, 1), (name, t)
        assert t["superseded"] == t["errors"] == 0
    assert topics["in:zb.junk"]["published"] == 0
    seen = received(sub)[-1][1]
    wait_for(lambda: received(sub)[-1][1] > seen + 10, "zb.good to go on")
    got = received(sub)
    assert all(ok for _, _, ok in got), "a damaged sample was published"
    counters = [counter for _, counter, _ in got]
    assert counters == list(range(counters[0], counters[0] + len(counters)))
    assert bridge_b.poll() is None
    text = log_text(bridge_b)
    assert "sample dropped: no attachment" in text and "(counted as bad_size)" in text
