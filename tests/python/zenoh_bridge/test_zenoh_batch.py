"""Batches between two bridges (docs/zenoh.md "Batches between bridges"; native core only): taken
when the sending bridge offers them and the receiving one accepts them, per-topic samples
otherwise (a bridge with --batch off, or on the Python path), every sample in order either
way; a plain Zenoh subscriber of the per-topic key sees every sample unbatched meanwhile;
malformed batches are counted and dropped while another topic flows.  Assertions are about
what arrived and what the counters say, never how fast."""

from __future__ import annotations

import re
from collections.abc import Iterator

import pytest
from netlab import HostProcess, NetLab
from polling import wait_for
from zenoh_sites import (
    Site,
    log_text,
    received,
    site_pair,
    start_managers,
    wait_log,
)

COUNT = 3000
QUEUED = "zb.*,queued=512"
_RAW_GOT = re.compile(r"got (\d+) (\d+) OK$")


@pytest.fixture
def native_sites(netlab: NetLab) -> Iterator[tuple[Site, Site]]:
    """Sites a and b whose bridges carry topic samples through the native core."""
    yield from site_pair(netlab, native=True)


def _raw_received(proc: HostProcess) -> list[tuple[int, int]]:
    """(seq, counter) of every sample a `zb_raw.py sub` printed."""
    return [(int(m[1]), int(m[2]))
            for m in map(_RAW_GOT.match, log_text(proc).splitlines()) if m]


def _stream(a: Site, b: Site, a_args: list[str], b_args: list[str], batched: bool,
            plain: bool = False) -> tuple[HostProcess, HostProcess, HostProcess | None]:
    """Bridges a (--out) and b (--in) of QUEUED with extra args, a subscriber of zb.log at b
    (and a plain Zenoh one of a's per-topic key if `plain`), then (once b takes batches if
    `batched`) COUNT samples from a; returns the bridges and the plain subscriber once b's
    subscriber has them all."""
    start_managers(a, b)
    bridge_a = a.bridge("--listen", a.endpoint, "--out", QUEUED, *a_args)
    bridge_b = b.bridge("--connect", a.endpoint, "--remote", a.prefix, "--in", QUEUED,
                        *b_args)
    raw = None
    if plain:
        raw = b.raw("sub", f"{a.prefix}/topic/zb.log", "--connect", a.endpoint)
        wait_log(raw, "^subscribed")
    wait_log(bridge_b, r"remote bridge ln/a is up")
    if batched:
        wait_log(bridge_b, r"topics from ln/a: samples come in batches")
    sub = b.peer("sub", "zb.log", "zbtest/sample", "--buffers", "1024")
    wait_log(sub, "^subscribed")
    a.peer("pub", "zb.log", "zbtest/sample", "--count", str(COUNT), "--wait-subscribers", "1",
           "--wait")
    got = wait_for(lambda: len(r := received(sub)) >= COUNT and r, f"{COUNT} samples at b")
    assert [counter for _, counter, _ in got] == list(range(1, COUNT + 1)), "lost or reordered"
    assert all(ok for _, _, ok in got), "a sample's value was damaged"
    return bridge_a, bridge_b, raw


def test_bridges_negotiate_batches(native_sites: tuple[Site, Site]) -> None:
    a, b = native_sites
    bridge_a, bridge_b, _ = _stream(a, b, [], [], batched=True)
    out = a.stats(bridge_a)["topics"]["out:zb.log"]
    into = b.stats(bridge_b)["topics"]["in:zb.log"]
    assert (out["sent"], into["received"], into["published"]) == (COUNT, COUNT, COUNT)
    # batches that came before the topic was set up at b went through Python, uncounted
    assert out["batches"] >= 1 and 1 <= into["batches"] <= out["batches"]
    assert into["gaps"] == into["bad_attachment"] == into["bad_batches"] == 0


@pytest.mark.parametrize("side", ["sender", "receiver", "receiver_python"])
def test_falls_back_when_the_peer_does_not_offer_batches(native_sites: tuple[Site, Site],
                                                         side: str) -> None:
    """The sender does not offer them (--batch off: an older bridge declares no offer), or the
    receiver does not take them (--batch off, or the Python path)."""
    a, b = native_sites
    a_args = ["--batch", "off"] if side == "sender" else []
    b_args = ["--batch", "off"] if side == "receiver" else []
    if side == "receiver_python":
        b.native = False  # --native off
    bridge_a, bridge_b, _ = _stream(a, b, a_args, b_args, batched=False)
    out = a.stats(bridge_a)["topics"]["out:zb.log"]
    into = b.stats(bridge_b)["topics"]["in:zb.log"]
    assert (out["sent"], into["published"]) == (COUNT, COUNT)
    assert out["batches"] == into["batches"] == 0
    assert "come in batches" not in log_text(bridge_b)


def test_plain_subscriber_of_the_topic_key_sees_every_sample_unbatched(
        native_sites: tuple[Site, Site]) -> None:
    a, b = native_sites
    bridge_a, bridge_b, raw = _stream(a, b, [], [], batched=True, plain=True)
    assert raw is not None
    got = wait_for(lambda: len(r := _raw_received(raw)) >= COUNT and r,
                   f"{COUNT} samples at the plain subscriber")
    assert [counter for _, counter in got] == list(range(1, COUNT + 1))
    assert [seq for seq, _ in got] == list(range(got[0][0], got[0][0] + COUNT))
    assert "batch" not in log_text(raw)  # never a batch on the per-topic key
    out = a.stats(bridge_a)["topics"]["out:zb.log"]
    into = b.stats(bridge_b)["topics"]["in:zb.log"]
    assert out["batches"] >= 1 and into["published"] == COUNT


def test_malformed_batches_are_counted_and_dropped(native_sites: tuple[Site, Site]) -> None:
    a, b = native_sites
    start_managers(a, b)
    bridge_a = a.bridge("--listen", a.endpoint, "--out", QUEUED)
    # zb.raw from a plain Zenoh session posing as a batching bridge ln/fake (zb_raw.py batches)
    bridge_b = b.bridge("--connect", a.endpoint, "--remote", a.prefix,
                        "--in", "zb.raw,queued=64,remote=ln/fake", "--in", QUEUED)
    wait_log(bridge_b, r"topics from ln/a: samples come in batches")
    good = b.peer("sub", "zb.log", "zbtest/sample", "--buffers", "1024")
    bad = b.peer("sub", "zb.raw", "zbtest/sample", "--buffers", "64")
    wait_log(good, "^subscribed")
    wait_log(bad, "^subscribed")
    a.peer("pub", "zb.log", "zbtest/sample", "--count", "0", "--rate", "500",
           "--wait-subscribers", "1", "--wait")
    wait_for(lambda: len(received(good)) >= 50, "zb.log flowing")
    raw = a.raw("batches", "ln/fake", "zb.raw", "--connect", a.endpoint)
    sent = int(wait_log(raw, r"^sent (\d+)$")[1])
    got = wait_for(lambda: len(r := received(bad)) >= 7 and r, "zb.raw's good samples at b")
    assert [counter for _, counter, _ in got] == list(range(1, 8))
    before = len(received(good))
    wait_for(lambda: len(received(good)) > before + 50, "zb.log still flowing")
    flowing = received(good)
    assert [c for _, c, _ in flowing] == list(range(1, len(flowing) + 1))
    stats = b.stats(bridge_b)
    dropped = stats["bad_batches"] + stats["topics"]["in:zb.raw"]["bad_batches"]
    assert dropped == sent
    assert stats["topics"]["in:zb.raw"]["published"] == 7
    assert stats["topics"]["in:zb.log"]["bad_batches"] == 0
    assert "dropped: batch magic" in log_text(bridge_b)
    assert a.stats(bridge_a)["topics"]["out:zb.log"]["errors"] == 0


def test_batch_setting() -> None:
    from links_and_nodes.zenoh_bridge.cli import build_config, parser
    from links_and_nodes.zenoh_bridge.config import ConfigError, from_dict

    rule = [{"match": "x", "direction": "out"}]
    assert from_dict({"topics": rule}).batch is True
    assert from_dict({"batch": False, "topics": rule}).batch is False
    with pytest.raises(ConfigError, match="batch must be true or false"):
        from_dict({"batch": "off", "topics": rule})
    args = parser().parse_args(["--out", "x", "--batch", "off"])
    assert build_config(args).batch is False
    with pytest.raises(SystemExit) as exc:
        parser().parse_args(["--out", "x", "--batch", "maybe"])
    assert exc.value.code == 2
