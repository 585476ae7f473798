"""The fault rules of ln_relay without sockets: DatagramShaper and StreamShaper driven with
made-up times and scripted random numbers, FaultSpec's validation and address parsing."""

from __future__ import annotations

import random

import pytest

from links_and_nodes.relay import FaultSpec, parse_address
from links_and_nodes.relay.shaping import DRAWS_PER_DATAGRAM, DatagramShaper, StreamShaper
from links_and_nodes.relay.stats import DirectionStats


class Scripted(random.Random):
    """Returns the given numbers, then 0.5 forever."""

    def __init__(self, values: list[float]) -> None:
        super().__init__(0)
        self.values = list(values)

    def random(self) -> float:
        return self.values.pop(0) if self.values else 0.5


def datagrams(faults: FaultSpec, rng: random.Random) -> tuple[DatagramShaper[int],
                                                              DirectionStats]:
    stats = DirectionStats("udp")
    return DatagramShaper[int](faults, rng, stats), stats


def drain(shaper: DatagramShaper[int], now: float = 1e9) -> list[int]:
    return [item for item, _ in shaper.pop_due(now)]


def lost_indices(seed: int, loss: float, count: int = 2000) -> set[int]:
    shaper, _ = datagrams(FaultSpec(loss=loss), random.Random(seed))
    for i in range(count):
        shaper.push(i, 10, 0.0)
    return set(range(count)) - set(drain(shaper))


def test_loss_is_reproducible_and_nested() -> None:
    low, again, other = lost_indices(1, 0.1), lost_indices(1, 0.1), lost_indices(2, 0.1)
    assert low == again
    assert low != other
    assert 140 <= len(low) <= 260
    # A fixed number of draws per datagram: more loss loses the same ones and more.
    assert low < lost_indices(1, 0.2)


def test_a_fixed_number_of_draws_per_datagram() -> None:
    rng = random.Random(5)
    shaper, stats = datagrams(FaultSpec(loss=0.5, duplicate=0.5, jitter_ms=3), rng)
    for i in range(100):
        shaper.push(i, 1, 0.0)
    reference = random.Random(5)
    for _ in range(100 * DRAWS_PER_DATAGRAM):
        reference.random()
    assert rng.random() == reference.random()
    assert 0 < stats.lost < 100


def test_delay_and_jitter_stay_in_bounds_and_never_negative() -> None:
    shaper, _ = datagrams(FaultSpec(delay_ms=10, jitter_ms=5), random.Random(3))
    for i in range(500):
        shaper.push(i, 1, 100.0)
    dues = []
    while (wakeup := shaper.next_wakeup()) is not None:
        dues.append(wakeup)
        assert len(drain(shaper, wakeup)) >= 1
    assert all(100.005 <= due <= 100.015 for due in dues)
    assert dues == sorted(dues)

    shaper, _ = datagrams(FaultSpec(delay_ms=2, jitter_ms=5), random.Random(3))
    for i in range(500):
        shaper.push(i, 1, 100.0)
    first = shaper.next_wakeup()
    assert first == 100.0  # clamped at no delay, not before the datagram arrived
    assert len(drain(shaper, 100.0)) > 100  # about 3/10 of them are clamped to 0


def test_jitter_reorders_and_equal_times_keep_arrival_order() -> None:
    shaper, _ = datagrams(FaultSpec(delay_ms=5, jitter_ms=5), random.Random(9))
    for i in range(200):
        shaper.push(i, 1, 0.0)
    out = drain(shaper)
    assert sorted(out) == list(range(200))
    assert out != list(range(200))

    shaper, _ = datagrams(FaultSpec(delay_ms=5), random.Random(9))
    for i in range(200):
        shaper.push(i, 1, 0.0)
    assert drain(shaper) == list(range(200))


def test_reorder_holds_a_datagram_behind_the_next() -> None:
    # Draws per datagram: loss, duplicate, reorder, delay, delay of the copy.
    hold, keep = [0.9, 0.9, 0.0, 0.5, 0.5], [0.9, 0.9, 0.9, 0.5, 0.5]
    lose = [0.0, 0.9, 0.9, 0.5, 0.5]
    rng = Scripted(hold + lose + keep + keep + hold + hold + keep)
    shaper, stats = datagrams(FaultSpec(loss=0.5, reorder=0.5, reorder_flush_ms=100), rng)
    shaper.push(0, 1, 0.0)  # held
    assert drain(shaper, 0.0) == []
    assert shaper.next_wakeup() == pytest.approx(0.1)
    shaper.push(1, 1, 0.0)  # lost: not a follower
    shaper.push(2, 1, 0.0)  # follower of 0
    shaper.push(3, 1, 0.0)
    shaper.push(4, 1, 0.0)  # held
    shaper.push(5, 1, 0.0)  # drawn for reordering while 4 is held: 4's follower instead
    shaper.push(6, 1, 0.0)
    assert drain(shaper, 0.0) == [2, 0, 3, 5, 4, 6]
    assert (stats.reordered, stats.lost, stats.units_in) == (2, 1, 7)


def test_a_held_datagram_without_follower_goes_after_the_flush_time() -> None:
    shaper, stats = datagrams(FaultSpec(reorder=1.0, reorder_flush_ms=20), random.Random(1))
    shaper.push(0, 1, 5.0)
    assert shaper.next_wakeup() == pytest.approx(5.02)
    assert drain(shaper, 5.019) == []
    assert drain(shaper, 5.02) == [0]
    assert stats.reordered == 0  # nothing overtook it
    assert shaper.next_wakeup() is None


def test_always_reordering_swaps_pairs() -> None:
    shaper, stats = datagrams(FaultSpec(reorder=1.0), random.Random(1))
    for i in range(10):
        shaper.push(i, 1, 0.0)
    assert drain(shaper) == [1, 0, 3, 2, 5, 4, 7, 6, 9, 8]
    assert stats.reordered == 5


def test_duplicates_are_counted_and_sent_twice() -> None:
    shaper, stats = datagrams(FaultSpec(duplicate=1.0), random.Random(1))
    for i in range(5):
        shaper.push(i, 3, 0.0)
    assert drain(shaper) == [0, 0, 1, 1, 2, 2, 3, 3, 4, 4]
    assert (stats.duplicated, stats.units_in, stats.bytes_in) == (5, 5, 15)


def test_the_queue_is_bounded() -> None:
    shaper, stats = datagrams(FaultSpec(delay_ms=1000, queue_limit=1000), random.Random(1))
    for i in range(25):
        shaper.push(i, 100, 0.0)
    assert (stats.queued, stats.queued_bytes, stats.overflowed) == (10, 1000, 15)
    assert drain(shaper, 0.5) == []
    assert drain(shaper, 1.0) == list(range(10))
    assert (stats.queued, stats.queued_bytes) == (0, 0)
    shaper.push(99, 100, 1.0)
    assert stats.queued == 1


def test_no_faults_means_no_draws_and_no_delay() -> None:
    rng = random.Random(4)
    state = rng.getstate()
    shaper, stats = datagrams(FaultSpec(), rng)
    for i in range(50):
        shaper.push(i, 1, 2.0)
    assert drain(shaper, 2.0) == list(range(50))
    assert rng.getstate() == state


def streams(faults: FaultSpec, rng: random.Random) -> tuple[StreamShaper, DirectionStats]:
    stats = DirectionStats("tcp")
    return StreamShaper(faults, rng, stats), stats


def test_stream_chunks_keep_their_order_under_jitter() -> None:
    shaper, stats = streams(FaultSpec(delay_ms=5, jitter_ms=5), random.Random(2))
    dues = [shaper.admit(100, i * 0.001)[0] for i in range(300)]
    assert dues == sorted(dues)
    assert all(due >= i * 0.001 for i, due in enumerate(dues))
    assert len(set(dues)) < len(dues)  # some chunks caught up with the one ahead
    assert (stats.duplicated, stats.reordered, stats.units_in) == (None, None, 300)


def test_a_lost_chunk_waits_doubling_timeouts_and_blocks_what_follows() -> None:
    faults = FaultSpec(loss=0.5, delay_ms=10, rto_ms=100, rto_max_ms=300)
    # Lost three times (0.1 < 0.5), then through (0.9), then a delay draw of 0.5: 10 ms.
    shaper, stats = streams(faults, Scripted([0.1, 0.1, 0.1, 0.9, 0.5, 0.9, 0.5]))
    due, give_up = shaper.admit(1, 0.0)
    assert not give_up
    assert due == pytest.approx(0.1 + 0.2 + 0.3 + 0.01)  # 400 ms capped at 300
    assert stats.lost == 3
    behind, _ = shaper.admit(1, 0.001)  # not lost, but behind the lost one
    assert behind == due


def test_tcp_gives_up_after_the_retries() -> None:
    faults = FaultSpec(loss=1.0, rto_ms=100, rto_max_ms=1000, tcp_retries=2)
    shaper, stats = streams(faults, random.Random(1))
    due, give_up = shaper.admit(1, 0.0)
    assert give_up
    assert due == pytest.approx(0.1 + 0.2 + 0.4)  # the original and two retransmissions
    assert stats.lost == 3


def test_eof_goes_behind_the_data() -> None:
    shaper, _ = streams(FaultSpec(loss=0.5, rto_ms=50), Scripted([0.1, 0.9, 0.5]))
    due, _ = shaper.admit(1, 0.0)
    assert shaper.eof_due(0.001) == due == pytest.approx(0.05)


def test_one_way_keeps_the_limits_but_no_faults_downstream() -> None:
    faults = FaultSpec(loss=0.3, delay_ms=4, jitter_ms=1, duplicate=0.1, reorder=0.1,
                       queue_limit=1234, one_way=True)
    assert faults.for_direction(upstream=True) is faults
    down = faults.for_direction(upstream=False)
    assert down.harmless and down.queue_limit == 1234
    assert FaultSpec(loss=0.3).for_direction(upstream=False).loss == 0.3


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"loss": 1.5}, "loss must be a probability in 0..1, not 1.5"),
    ({"duplicate": -0.1}, "duplicate must be a probability"),
    ({"reorder": float("nan")}, "reorder must be a probability"),
    ({"loss": True}, "loss must be a probability"),
    ({"delay_ms": -1}, "delay_ms must be a finite number of milliseconds >= 0"),
    ({"jitter_ms": float("inf")}, "jitter_ms must be a finite number"),
    ({"rto_ms": 0}, "rto_ms must be > 0"),
    ({"rto_ms": 500, "rto_max_ms": 100}, "rto_max_ms (100) must be at least rto_ms (500)"),
    ({"queue_limit": 0}, "queue_limit must be an integer >= 1"),
    ({"tcp_chunk": 1.5}, "tcp_chunk must be an integer >= 1"),
])
def test_fault_spec_rejects_nonsense(kwargs: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError) as info:
        FaultSpec(**kwargs)  # type: ignore[arg-type]
    assert message in str(info.value)


@pytest.mark.parametrize(("text", "expected"), [
    ("127.0.0.1:5000", ("127.0.0.1", 5000)),
    ("[::1]:0", ("::1", 0)),
    ("robot-a:65535", ("robot-a", 65535)),
])
def test_addresses(text: str, expected: tuple[str, int]) -> None:
    assert parse_address(text, allow_port_zero=True) == expected


@pytest.mark.parametrize(("text", "message"), [
    ("127.0.0.1", "expected HOST:PORT"),
    (":5000", "expected HOST:PORT"),
    ("::1:5000", "an IPv6 address needs brackets"),
    ("[1.2.3.4]:5", "brackets are for IPv6 addresses"),
    ("host:0", "the port must be a number 1..65535"),
    ("host:70000", "the port must be a number 1..65535"),
    ("host:x", "the port must be a number 1..65535"),
])
def test_bad_addresses(text: str, message: str) -> None:
    with pytest.raises(ValueError, match=message.replace(".", r"\.")):
        parse_address(text)
