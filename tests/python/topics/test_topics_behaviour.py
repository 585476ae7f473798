"""Topic semantics end to end: queued delivery without loss, exact overrun counts, latest
mode, timeouts, zero-copy, layout mismatches, limits, and ring growth under a publisher."""

from __future__ import annotations

import threading
import time

import pytest

import links_and_nodes as ln

from .conftest import Manager, wait_ready


def test_sixteen_queued_subscribers_lose_nothing(manager: Manager) -> None:
    n = 100_000
    subs = [manager.tool("sub-pattern", "stress", str(n), "64", "30") for _ in range(16)]
    for s in subs:
        wait_ready(s)
    pub = manager.tool("pub-pattern", "stress", str(n), "wait")
    assert pub.wait(timeout=600) == 0
    for s in subs:
        out, _ = s.communicate(timeout=600)
        assert s.returncode == 0
        assert out.split() == ["received", str(n), "torn", "0", "disorder", "0", "overruns", "0",
                               "timeouts", "0", "last", str(n), "value", str(n)]


def test_too_few_buffers_count_overruns_exactly(manager: Manager) -> None:
    with manager.client() as clnt:
        sub = clnt.subscribe("t.overrun", "robot/joint_state", buffers=10)
        pub = clnt.publish("t.overrun", "robot/joint_state")
        for i in range(1, 101):
            pub.packet.cycle = i
            pub.write()
        first = sub.read(timeout=1)
        assert first is not None and first.cycle == 91
        assert sub.info.overruns == 90 and sub.info.seq == 91
        cycles = [first.cycle]
        while (pkt := sub.read(timeout=0)) is not None:
            cycles.append(pkt.cycle)
            assert sub.info.overruns == 0
        assert cycles == list(range(91, 101))
        assert sub.overruns == 90


def test_latest_mode_returns_the_newest_sample(manager: Manager) -> None:
    with manager.client() as clnt:
        pub = clnt.publish("t.latest", "robot/joint_state")
        for i in range(1, 6):
            pub.packet.cycle = i
            pub.write()
        sub = clnt.subscribe("t.latest", "robot/joint_state")
        pkt = sub.read(timeout=1)
        assert pkt is not None and pkt.cycle == 5 and sub.info.seq == 5
        assert sub.read(timeout=0) is None  # nothing newer
        pub.packet.cycle = 6
        pub.write()
        pkt = sub.read(timeout=0)
        assert pkt is not None and pkt.cycle == 6


def test_read_timeout_and_nonblocking(manager: Manager) -> None:
    with manager.client() as clnt:
        sub = clnt.subscribe("t.quiet", "robot/joint_state", buffers=4)
        assert sub.read(timeout=0) is None
        assert clnt.last_error == (0, "")  # "nothing yet" is not an error
        assert sub.read(timeout=0.05) is None
        assert "no sample on topic 't.quiet'" in ln._clientlib.last_error()
        code, text = clnt.last_error  # kept on the client too, for other threads
        assert code == ln.LnTimeoutError.code and "t.quiet" in text


def test_zero_copy_write_and_read(manager: Manager) -> None:
    with manager.client() as clnt:
        pub = clnt.publish("t.big", "lntest/pattern")
        sub = clnt.subscribe("t.big", "lntest/pattern", buffers=4)
        with pub.loan() as msg:
            msg.word[:] = 7
        with pytest.raises(RuntimeError):
            with pub.loan() as msg:
                msg.word[:] = 8
                raise RuntimeError("aborted: nothing is published")
        with sub.borrow(timeout=1) as msg:
            assert msg is not None and set(msg.word.tolist()) == {7}
        assert sub.read(timeout=0) is None
        with sub.borrow(timeout=0) as msg:
            assert msg is None


def test_zero_copy_waits_longer_than_one_slice(manager: Manager) -> None:
    """A borrow waits across libln's wait slices for a sample published later; a loan on a
    publisher that waits for a full queue times out as asked."""
    with manager.client() as clnt:
        pub = clnt.publish("t.zcwait", "lntest/pattern", wait_for_subscribers=True)
        sub = clnt.subscribe("t.zcwait", "lntest/pattern", buffers=2)
        later = threading.Timer(0.35, pub.write)
        later.start()
        start = time.monotonic()
        with sub.borrow(timeout=10) as msg:
            assert msg is not None and sub.info.seq == 1
        assert time.monotonic() - start >= 0.3
        later.join()
        pub.write()
        pub.write()  # the subscriber's two buffers are full: a loan must wait
        start = time.monotonic()
        with pytest.raises(ln.LnTimeoutError):
            with pub.loan(timeout=0.35):
                pass
        assert time.monotonic() - start >= 0.3
        assert sub.read(timeout=0) is not None  # room again: the loan goes through
        with pub.loan(timeout=1) as msg:
            msg.word[:] = 3
        assert [sub.read(timeout=0) is not None for _ in range(2)] == [True, True]


def test_borrowed_sample_overwritten_is_reported(manager: Manager) -> None:
    with manager.client() as clnt:
        pub = clnt.publish("t.wrap", "lntest/pattern")
        sub = clnt.subscribe("t.wrap", "lntest/pattern")  # latest: a 2-slot ring
        pub.write()
        with pytest.raises(ln.LnOverrunError):
            with sub.borrow(timeout=1) as msg:
                assert msg is not None
                pub.write()
                pub.write()  # the publisher comes around to the borrowed slot


def test_layout_mismatch_names_both_definitions(manager: Manager) -> None:
    with manager.client() as clnt:
        clnt.publish("t.layout", "robot/joint_state")
        with pytest.raises(ln.LnLayoutError) as err:
            clnt.subscribe("t.layout", "robot/command")
        text = str(err.value)
        assert "robot/joint_state" in text and "robot/command" in text
        assert "0xef8f8ef877c98834" in text


def test_ring_grows_under_a_running_publisher(manager: Manager) -> None:
    with manager.client() as clnt:
        pub = clnt.publish("t.grow", "robot/joint_state")
        small = clnt.subscribe("t.grow", "robot/joint_state", buffers=2)
        pub.packet.cycle = 1
        pub.write()
        big = clnt.subscribe("t.grow", "robot/joint_state", buffers=500)  # new generation
        for i in range(2, 402):
            pub.packet.cycle = i
            pub.write()
        got = []
        while (pkt := big.read(timeout=0)) is not None:
            got.append(pkt.cycle)
        assert got == list(range(2, 402))
        assert big.overruns == 0
        # The small queued reader drains the old ring, then moves on: it keeps its newest 2.
        assert [small.read(timeout=0).cycle for _ in range(3)] == [1, 400, 401]
        assert small.overruns == 398


def test_counts(manager: Manager) -> None:
    with manager.client() as clnt:
        pub = clnt.publish("t.count", "robot/joint_state")
        subs = [clnt.subscribe("t.count", "robot/joint_state") for _ in range(3)]
        assert pub.subscriber_count == 3 and subs[0].publisher_count == 1
        clnt.unsubscribe(subs.pop())
        assert pub.subscriber_count == 2


def test_limits(manager: Manager) -> None:
    with manager.client() as clnt:
        ports = [clnt.publish(f"t.many.{i}", "robot/joint_state") for i in range(1000)]
        assert len(ports) == 1000
        subs = [clnt.subscribe("t.fan", "robot/joint_state") for _ in range(64)]
        with pytest.raises(ln.LnLimitError, match="64"):
            clnt.subscribe("t.fan", "robot/joint_state")
        with pytest.raises(ln.LnLimitError):
            clnt.subscribe("t.deep", "robot/joint_state", buffers=1025)
        deep = clnt.subscribe("t.deep", "robot/joint_state", buffers=1024)
        assert deep.read(timeout=0) is None
        assert len(subs) == 64


def test_largest_message(manager: Manager, tmp_path) -> None:
    md_dir = tmp_path / "md"
    (md_dir / "lnbig").mkdir(parents=True)
    (md_dir / "lnbig" / "frame").write_text("uint8_t data[64*1024*1024]\n")
    (md_dir / "lnbig" / "toobig").write_text("uint8_t data[64*1024*1024 + 1]\n")
    ln.add_message_definition_dir(md_dir)
    with manager.client() as clnt:
        pub = clnt.publish("t.frame", "lnbig/frame")
        sub = clnt.subscribe("t.frame", "lnbig/frame")
        with pub.loan() as msg:
            msg.data[-1] = 42
        with sub.borrow(timeout=5) as msg:
            assert msg is not None and msg.data[-1] == 42
        with pytest.raises(ln.LnLimitError):
            clnt.publish("t.huge", "lnbig/toobig")
