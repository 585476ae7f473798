"""Regression tests for ring growth and waiting publishers: queued readers lose nothing
across several generations, nobody deadlocks, a waiting publisher does not block
other publishers, and loans stay with their thread."""

from __future__ import annotations

import math
import threading

import pytest

import links_and_nodes as ln

from .conftest import Manager

MD = "robot/joint_state"


def write(pub: ln.publisher, cycle: int, timeout: float | None = 0) -> None:
    pub.packet.cycle = cycle
    pub.write(timeout=timeout)


def cycles(sub: ln.subscriber) -> list[int]:
    out = []
    while (pkt := sub.read(timeout=0)) is not None:
        out.append(pkt.cycle)
    return out


def test_queued_reader_keeps_every_sample_across_two_growths(manager: Manager) -> None:
    with manager.client() as clnt:
        pub = clnt.publish("g.two", MD)
        reader = clnt.subscribe("g.two", MD, buffers=20)
        write(pub, 1)
        clnt.subscribe("g.two", MD, buffers=40)    # generation 2
        for i in range(2, 5):
            write(pub, i)
        clnt.subscribe("g.two", MD, buffers=100)   # generation 3
        for i in range(5, 8):
            write(pub, i)
        assert cycles(reader) == list(range(1, 8))
        assert reader.overruns == 0


def test_waiting_publisher_and_queued_reader_across_growth(manager: Manager) -> None:
    with manager.client() as clnt:
        pub = clnt.publish("g.wait", MD, wait_for_subscribers=True)
        queued = clnt.subscribe("g.wait", MD, buffers=2)
        write(pub, 1)
        write(pub, 2)                               # the queued reader is now full
        clnt.subscribe("g.wait", MD, buffers=16)    # grows the ring under both
        errors: list[BaseException] = []

        def third() -> None:
            try:
                write(pub, 3, timeout=30)           # waits for the queued reader
            except BaseException as exc:  # noqa: BLE001 - reported below
                errors.append(exc)

        writer = threading.Thread(target=third)
        writer.start()
        got = [queued.read(timeout=30).cycle for _ in range(3)]
        writer.join(timeout=60)
        assert not writer.is_alive() and errors == []
        assert got == [1, 2, 3]


def test_latest_subscriber_after_growth_waits_for_the_next_sample(manager: Manager) -> None:
    with manager.client() as clnt:
        pub = clnt.publish("g.latest", MD)
        write(pub, 1)
        clnt.subscribe("g.latest", MD, buffers=8)   # generation 2, no sample in it yet
        latest = clnt.subscribe("g.latest", MD)
        assert latest.read(timeout=0) is None
        assert latest.read(timeout=0.05) is None
        write(pub, 2)
        pkt = latest.read(timeout=5)
        assert pkt is not None and pkt.cycle == 2


def test_waiting_publisher_does_not_block_other_publishers(manager: Manager) -> None:
    with manager.client() as clnt:
        waiting = clnt.publish("g.two_pubs", MD, wait_for_subscribers=True)
        plain = clnt.publish("g.two_pubs", MD)
        queued = clnt.subscribe("g.two_pubs", MD, buffers=2)
        write(waiting, 1)
        write(waiting, 2)
        blocked = threading.Thread(target=write, args=(waiting, 3, 30))
        blocked.start()
        try:
            for i in range(10, 20):
                write(plain, i, timeout=0)          # never EAGAIN: nobody holds the lock
        finally:
            assert queued.read(timeout=5) is not None  # frees a buffer: the waiter goes on
            blocked.join(timeout=60)
        assert not blocked.is_alive()


def test_loan_belongs_to_its_thread(manager: Manager) -> None:
    with manager.client() as clnt:
        pub = clnt.publish("g.loan", MD)
        sub = clnt.subscribe("g.loan", MD)
        loan = pub.loan()
        msg = loan.__enter__()
        msg.cycle = 5
        failure: list[BaseException] = []

        def commit_elsewhere() -> None:
            try:
                ln._clientlib.ln_write_commit(pub.handle)
            except BaseException as exc:  # noqa: BLE001 - inspected below
                failure.append(exc)

        other = threading.Thread(target=commit_elsewhere)
        other.start()
        other.join()
        assert len(failure) == 1 and isinstance(failure[0], ln.LnBusyError)
        loan.__exit__(None, None, None)             # the owner commits
        pkt = sub.read(timeout=5)
        assert pkt is not None and pkt.cycle == 5


def test_timeouts_nan_and_infinite(manager: Manager) -> None:
    with manager.client() as clnt:
        pub = clnt.publish("g.timeouts", MD)
        sub = clnt.subscribe("g.timeouts", MD)
        with pytest.raises(ln.LnInvalError, match="NaN"):
            sub.read(timeout=math.nan)
        later = threading.Timer(0.05, write, args=(pub, 9))
        later.start()
        pkt = sub.read(timeout=math.inf)            # waits, as for None
        later.join()
        assert pkt is not None and pkt.cycle == 9


def test_overruns_found_but_not_yet_read_are_counted(manager: Manager) -> None:
    with manager.client() as clnt:
        pub = clnt.publish("g.pending", MD)
        sub = clnt.subscribe("g.pending", MD, buffers=2)
        for i in range(1, 11):
            write(pub, i)
        assert sub.overruns == 0                    # nothing looked at yet
        assert cycles(sub) == [9, 10]
        assert sub.overruns == 8
