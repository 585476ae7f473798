"""The Python pull consumer (links_and_nodes.pull over libln_pull's DIT core) against a
producer written in Python (fake_producer.py): samples in increasing seq with the bytes
published, md decoding, sync giving the latest, LpPacket replies, NACK jumps, an HMAC
producer, the naive and polling modes, and the argument checks."""

from __future__ import annotations

import struct

import pytest

import links_and_nodes as ln
from links_and_nodes import md_loader
from links_and_nodes.pull import make_options

from .fake_producer import FakeProducer

LIMIT = 10.0


def payload(seq: int) -> bytes:
    return struct.pack("<QQ", seq, seq * 7)


def take(sub: ln.pull.PullSubscription, n: int) -> list[ln.PullSample]:
    out = []
    while len(out) < n:
        sample = sub.receive(LIMIT)
        assert sample is not None, f"no sample after {len(out)}; stats {sub.stats}"
        out.append(sample)
    return out


@pytest.mark.parametrize("lp", [False, True])
def test_samples_in_order_with_their_bytes(lp: bool) -> None:
    with FakeProducer("/t/a.b", payload, lp=lp) as prod, \
            ln.pull_subscribe("127.0.0.1", prod.port, "/t/a.b", None) as sub:
        samples = take(sub, 30)
    seqs = [s.seq for s in samples]
    assert seqs == sorted(set(seqs)), seqs
    for s in samples:
        assert s.message == payload(s.seq)
        assert s.publish_time > 0 and s.age > -1.0
    assert prod.syncs >= 1
    stats = sub.stats
    assert stats.data >= 30 and stats.bad == 0 and stats.mismatched == 0


def test_first_sample_is_the_latest_by_sync() -> None:
    with FakeProducer("/t/x", payload, period_s=0.05) as prod:
        while prod.latest < 5:
            pass
        with ln.pull_subscribe("127.0.0.1", prod.port, "/t/x", None) as sub:
            first = take(sub, 1)[0]
    assert first.seq >= 5  # the latest when it asked, never an older one


def test_md_decoding_by_name_and_class() -> None:
    cls = md_loader.message_class("robot/joint_state")

    def joint(seq: int) -> bytes:
        m = cls()
        m.cycle = seq
        m.position[3] = seq / 2
        return bytes(m)

    for md in ("robot/joint_state", cls):
        with FakeProducer("/t/js", joint) as prod, \
                ln.pull_subscribe("127.0.0.1", prod.port, "/t/js", md) as sub:
            for s in take(sub, 5):
                assert isinstance(s.message, cls)
                assert s.message.cycle == s.seq and s.message.position[3] == s.seq / 2


def test_wrong_size_samples_are_counted_not_delivered() -> None:
    with FakeProducer("/t/w", lambda seq: b"short") as prod, \
            ln.pull_subscribe("127.0.0.1", prod.port, "/t/w", "robot/joint_state") as sub:
        assert sub.receive(0.5) is None
        assert sub.stats.mismatched > 0


def test_hmac_producer_and_naive_and_polling_modes() -> None:
    for kwargs in ({"naive": True}, {"poll_ms": 20}, {"window": 1}):
        with FakeProducer("/t/h", payload, key=b"k" * 16) as prod, \
                ln.pull_subscribe("127.0.0.1", prod.port, "/t/h", None, **kwargs) as sub:
            seqs = [s.seq for s in take(sub, 5)]
        assert seqs == sorted(set(seqs)), (kwargs, seqs)


def test_nack_jumps_ahead_of_a_lost_history() -> None:
    # history 1: any seq but the latest is NACKed at once; the consumer keeps up anyway
    with FakeProducer("/t/n", payload, period_s=0.002, history=1) as prod, \
            ln.pull_subscribe("127.0.0.1", prod.port, "/t/n", None) as sub:
        seqs = [s.seq for s in take(sub, 10)]
    assert seqs == sorted(set(seqs))


def test_options_and_bad_arguments() -> None:
    o = make_options(window=2, deadline_ms=250, overrides={"boot_after": 5})
    assert (o.window, o.t_max_ms, o.boot_after) == (2, 250, 5)
    naive = make_options(naive=True)
    assert (naive.window, naive.t_max_ms) == (1, 2000)
    with pytest.raises(ValueError, match="unknown pull option 'nope'"):
        make_options(overrides={"nope": 1})
    with pytest.raises(ValueError, match="cannot pull"):
        ln.pull_subscribe("127.0.0.1", 9, "no-slash", None)
    with pytest.raises(ValueError, match="cannot pull"):
        ln.pull_subscribe("127.0.0.1", 9, "/t/x", None, window=17)  # > LN_PULL_MAX_WINDOW


def test_nobody_at_the_port_times_out_quietly() -> None:
    with FakeProducer("/t/q", payload) as prod:
        port = prod.port
    with ln.pull_subscribe("127.0.0.1", port, "/t/q", None, deadline_ms=50) as sub:
        assert sub.receive(0.3) is None
        assert sub.stats.interests >= 2
