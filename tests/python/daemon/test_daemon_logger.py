"""Topic logging on the publisher's host: a daemon logger reads a real ring (taps inject the
samples a publisher would write) into its preallocated buffer while enabled and keeps it
when disabled; depth, divisor and span decide exactly what stays, and every sample is
counted as stored, skipped, dropped or missed.  Fetching in chunks gives the samples back in
order; the memory limit is checked when a topic is configured; a ring may appear after its
logger; loggers belong to their instance and outlive the connection; malformed requests
close only their connection; a publisher killed while being logged harms nothing."""

from __future__ import annotations

import asyncio
import math
import signal
import struct
import subprocess
import sys
from collections.abc import Awaitable, Callable, Iterator
from pathlib import Path

import pytest
from daemonproc import WAIT, Daemon, RawConnection, daemon_exe, stop_daemon, unique_instance
from ringtap import Tap, prefix, purge

from links_and_nodes.manager.processes import daemon_client as dc
from links_and_nodes.manager.processes import daemon_keys as dk
from links_and_nodes.manager.processes import daemon_wire as dw
from links_and_nodes.wire import codec as wc

LAYOUT, SIZE, SLOTS = 0x5EED_0003, 64, 256
TOPIC, MD = "/arm/state", "lntest/pattern"
FRAME = 4 << 20
# One sample has to fit a LOGGER_DATA reply: the frame minus header (5), tag (32), the reply's
# fields before its samples at their longest (8+8+4+255+1+8*8+4) and seq and timestamp (16).
MAX_LOGGED = FRAME - 5 - 32 - 344 - 16
HERE = Path(__file__).resolve().parent


def sample(seq: int, size: int = SIZE) -> bytes:
    return struct.pack("<Q", seq).ljust(size, b"\xcd")


def memory(depth: int, size: int = SIZE) -> int:
    """What docs/daemon.md says a buffer takes: depth + 1 slots of 16 bytes and the message
    rounded up to 8."""
    return (depth + 1) * (16 + (size + 7) // 8 * 8)


@pytest.fixture
def logged(daemon: Daemon) -> Iterator[Daemon]:
    """The daemon fixture, and every segment of its instance removed afterwards."""
    yield daemon
    purge(daemon.instance)


async def until(check: Callable[[], Awaitable[object]], what: str) -> object:
    """Poll `check` until it returns something true; WAIT is only an upper bound."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + WAIT
    while not (value := await check()):
        if loop.time() > deadline:
            pytest.fail(f"gave up waiting for {what}")
        await asyncio.sleep(0.01)
    return value


async def topic_status(client: dc.DaemonClient, logger: str,
                       topic: str = TOPIC) -> dw.LoggerTopicStatus:
    (found,) = [t for t in (await client.logger_status(logger)).topics if t.topic == topic]
    return found


async def received(client: dc.DaemonClient, logger: str, count: int,
                   topic: str = TOPIC) -> dw.LoggerTopicStatus:
    """Waits until the logger has taken `count` samples out of the ring (plus any it
    missed)."""

    async def check() -> dw.LoggerTopicStatus | None:
        s = await topic_status(client, logger, topic)
        assert s.received + s.missed <= count, s
        return s if s.received + s.missed == count else None

    status = await until(check, f"{count} samples to reach logger {logger}")
    assert isinstance(status, dw.LoggerTopicStatus)
    return status


def inject(tap: Tap, seqs: range | list[int], ts: Callable[[int], int] = lambda s: s * 1000,
           size: int = SIZE) -> None:
    for seq in seqs:
        tap.inject(sample(seq, size), seq, ts(seq))


async def refused(call: Awaitable[object], *texts: str,
                  code: dw.ErrorCode = dw.ErrorCode.LOGGER_FAILED) -> str:
    with pytest.raises(dw.DaemonError) as e:
        await call
    assert e.value.code == code, e.value
    for text in texts:
        assert text in str(e.value)
    return str(e.value)


def counts(chunk: dw.LoggerChunk | dw.LoggerTopicStatus) -> tuple[int, int, int, int, int]:
    return chunk.received, chunk.stored, chunk.missed, chunk.skipped, chunk.dropped


def test_logs_exactly_what_is_published_while_enabled(logged: Daemon) -> None:
    ring = prefix(logged.instance) + "1.1"

    async def first() -> None:
        async with await logged.connect() as client:
            await client.ring_create(ring, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await client.logger_topic("box", TOPIC, ring, MD, LAYOUT, SIZE, 100)
            status = await client.logger_status()
            assert status.memory_used == memory(100) and status.memory_limit == 256 << 20
            assert status.topics == [dw.LoggerTopicStatus(
                logger="box", topic=TOPIC, ring=ring, md_name=MD, enabled=False, depth=100,
                divisor=1, span=0.0, message_size=SIZE, received=0, stored=0, missed=0,
                skipped=0, dropped=0, last_error="")]
            with Tap(ring, LAYOUT, SIZE) as publisher:
                inject(publisher, range(1, 4))  # before the logger is enabled: not logged
                await client.logger_enable("box")
                inject(publisher, range(4, 14))
                await received(client, "box", 10)
                await client.logger_enable("box", enable=False)
                inject(publisher, range(14, 21))  # disabled: not logged
            chunk = await client.logger_fetch("box", TOPIC)
            assert [(s, t, d) for s, t, d in chunk.samples] == \
                [(seq, seq * 1000, sample(seq)) for seq in range(4, 14)]
            assert (chunk.message_size, chunk.layout_hash, chunk.md_name, chunk.enabled) == \
                (SIZE, LAYOUT, MD, False)
            assert counts(chunk) == (10, 10, 0, 0, 0)
            assert (chunk.first_seq, chunk.last_seq) == (4, 13)

    async def second() -> None:
        # A new connection of the instance finds the logger and its data as they were.
        async with await logged.connect() as client:
            chunk = await client.logger_fetch("box", TOPIC)
            assert [s for s, _, _ in chunk.samples] == list(range(4, 14))
            await client.logger_enable("box")  # the data stays; a fresh tap from now on
            with Tap(ring, LAYOUT, SIZE) as publisher:
                inject(publisher, [21, 22])
                status = await received(client, "box", 12)
                # what was published while disabled is not missed
                assert counts(status) == (12, 12, 0, 0, 0)
                chunk = await client.logger_fetch("box", TOPIC, after_seq=13)
                assert [s for s, _, _ in chunk.samples] == [21, 22]
                await client.logger_enable("box", clear=True)
                assert counts(await topic_status(client, "box")) == (0, 0, 0, 0, 0)
                inject(publisher, [23])
                await received(client, "box", 1)
            chunk = await client.logger_fetch("box", TOPIC)
            assert [s for s, _, _ in chunk.samples] == [23] and chunk.enabled
            assert (chunk.first_seq, chunk.last_seq) == (23, 23)

    asyncio.run(first())
    asyncio.run(second())


def test_depth_drops_exactly_the_oldest(logged: Daemon) -> None:
    ring = prefix(logged.instance) + "1.1"

    async def main() -> None:
        async with await logged.connect() as client:
            await client.ring_create(ring, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await client.logger_topic("box", TOPIC, ring, MD, LAYOUT, SIZE, 5)
            await client.logger_enable("box")
            with Tap(ring, LAYOUT, SIZE) as publisher:
                inject(publisher, range(1, 13))
                await received(client, "box", 12)
            chunk = await client.logger_fetch("box", TOPIC)
            assert [(s, d) for s, _, d in chunk.samples] == \
                [(seq, sample(seq)) for seq in range(8, 13)]
            assert counts(chunk) == (12, 5, 0, 0, 7)

    asyncio.run(main())


def test_divisor_keeps_multiples_and_counts_the_rest(logged: Daemon) -> None:
    ring = prefix(logged.instance) + "1.1"

    async def main() -> None:
        async with await logged.connect() as client:
            await client.ring_create(ring, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await client.logger_topic("box", TOPIC, ring, MD, LAYOUT, SIZE, 100, divisor=3)
            await client.logger_enable("box")
            with Tap(ring, LAYOUT, SIZE) as publisher:
                inject(publisher, range(1, 21))
                await received(client, "box", 20)
                chunk = await client.logger_fetch("box", TOPIC)
                assert [s for s, _, _ in chunk.samples] == [3, 6, 9, 12, 15, 18]
                assert counts(chunk) == (20, 6, 0, 14, 0)
                # The divisor changes without losing data.
                await client.logger_topic("box", TOPIC, ring, MD, LAYOUT, SIZE, 100, divisor=2)
                inject(publisher, range(21, 25))
                await received(client, "box", 24)
            chunk = await client.logger_fetch("box", TOPIC)
            assert [s for s, _, _ in chunk.samples] == [3, 6, 9, 12, 15, 18, 22, 24]
            assert counts(chunk) == (24, 8, 0, 16, 0)
            assert (await topic_status(client, "box")).divisor == 2

    asyncio.run(main())


def test_span_drops_samples_older_than_the_newest_minus_the_span(logged: Daemon) -> None:
    ring = prefix(logged.instance) + "1.1"
    step = 300_000_000  # ns between the samples' timestamps

    async def main() -> None:
        async with await logged.connect() as client:
            await client.ring_create(ring, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await client.logger_topic("box", TOPIC, ring, MD, LAYOUT, SIZE, 100, span=0.9)
            await client.logger_enable("box")
            with Tap(ring, LAYOUT, SIZE) as publisher:
                inject(publisher, range(1, 11), ts=lambda seq: seq * step)
                await received(client, "box", 10)
            chunk = await client.logger_fetch("box", TOPIC)
            # newest 3.0 s: 2.1 s (seq 7) is exactly the span old and stays, 1.8 s goes
            assert [(s, t) for s, t, _ in chunk.samples] == \
                [(seq, seq * step) for seq in range(7, 11)]
            assert counts(chunk) == (10, 4, 0, 0, 6)
            assert (await topic_status(client, "box")).span == 0.9

    asyncio.run(main())


def test_fetch_in_chunks_reassembles_exactly(logged: Daemon) -> None:
    ring = prefix(logged.instance) + "1.1"
    per = 16 + SIZE

    async def main() -> None:
        async with await logged.connect() as client:
            await client.ring_create(ring, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await client.logger_topic("box", TOPIC, ring, MD, LAYOUT, SIZE, 1000)
            await client.logger_enable("box")
            with Tap(ring, LAYOUT, SIZE) as publisher:
                inject(publisher, range(1, 201))
                await received(client, "box", 200)
            got: list[tuple[int, int, bytes]] = []
            after = 0
            while chunk := (await client.logger_fetch("box", TOPIC, after, 10 * per + per - 1)
                            ).samples:
                assert len(chunk) == 10
                got += chunk
                after = chunk[-1][0]
            assert got == [(seq, seq * 1000, sample(seq)) for seq in range(1, 201)]
            # at least one sample, however small max_bytes is
            for after in (0, 57, 199):
                one = await client.logger_fetch("box", TOPIC, after, 0)
                assert [s for s, _, _ in one.samples] == [after + 1]
            assert (await client.logger_fetch("box", TOPIC, 200)).samples == []
            assert len((await client.logger_fetch("box", TOPIC)).samples) == 200

    asyncio.run(main())


def test_large_samples_are_fetched_within_the_frame_limit(logged: Daemon) -> None:
    ring = prefix(logged.instance) + "1.1"
    size = 1 << 20

    async def main() -> None:
        async with await logged.connect() as client:
            await client.ring_create(ring, TOPIC, MD, LAYOUT, size, 8)
            await client.logger_topic("box", TOPIC, ring, MD, LAYOUT, size, 6)
            await client.logger_enable("box")
            with Tap(ring, LAYOUT, size) as publisher:
                inject(publisher, range(1, 6), size=size)
                await received(client, "box", 5)
            first = await client.logger_fetch("box", TOPIC, 0, 0xFFFFFFFF)
            # four samples of 1 MiB + 16 bytes would exceed the 4 MiB frame
            assert [s for s, _, _ in first.samples] == [1, 2, 3]
            rest = await client.logger_fetch("box", TOPIC, 3, 0xFFFFFFFF)
            assert [(s, d) for s, _, d in first.samples + rest.samples] == \
                [(seq, sample(seq, size)) for seq in range(1, 6)]
            # The largest message whose sample fits a reply, and one byte more.
            await client.logger_topic("huge", TOPIC, ring, MD, LAYOUT, MAX_LOGGED, 1)
            await refused(client.logger_topic("huge", TOPIC, ring, MD, LAYOUT, MAX_LOGGED + 1,
                                              1), f"message size {MAX_LOGGED + 1} out of range "
                          f"1..{MAX_LOGGED}")

    asyncio.run(main())


def test_memory_limit_is_checked_when_configured(start: Callable[..., Daemon]) -> None:
    daemon = start("--logger-memory", "64k")
    ring = prefix(daemon.instance) + "1.1"
    limit = 64 << 10

    async def main() -> None:
        async with await daemon.connect() as client:
            await client.ring_create(ring, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await client.logger_topic("small", TOPIC, ring, MD, LAYOUT, SIZE, 100)
            free = limit - memory(100)
            text = await refused(
                client.logger_topic("big", TOPIC, ring, MD, LAYOUT, SIZE, 800),
                "logger 'big' topic '/arm/state' needs", f"{memory(800)} bytes",
                f"only {free} of", f"limit of {limit} bytes", "--logger-memory")
            assert str(memory(800)) in text
            # A reallocation that would not fit leaves the topic as it was.
            await refused(client.logger_topic("small", TOPIC, ring, MD, LAYOUT, SIZE, 1000),
                          "logger 'small'", f"only {limit} of")
            status = await client.logger_status()
            assert (status.memory_limit, status.memory_used) == (limit, memory(100))
            assert [(t.logger, t.depth) for t in status.topics] == [("small", 100)]
            await refused(client.logger_status("big"), "no logger 'big'")
            # The logger that fits works.
            await client.logger_enable("small")
            with Tap(ring, LAYOUT, SIZE) as publisher:
                inject(publisher, range(1, 4))
                await received(client, "small", 3)
            chunk = await client.logger_fetch("small", TOPIC)
            assert [s for s, _, _ in chunk.samples] == [1, 2, 3]
            # Removing it frees its memory for the other one.
            await client.logger_remove("small")
            assert (await client.logger_status()).memory_used == 0
            await client.logger_topic("big", TOPIC, ring, MD, LAYOUT, SIZE, 800)
            assert (await client.logger_status()).memory_used == memory(800)

    try:
        asyncio.run(main())
    finally:
        purge(daemon.instance)


def test_logger_memory_zero_disables_logging(start: Callable[..., Daemon]) -> None:
    daemon = start("--logger-memory", "0")

    async def main() -> None:
        async with await daemon.connect() as client:
            await refused(client.logger_topic("box", TOPIC, prefix(daemon.instance) + "1.1", MD,
                                              LAYOUT, SIZE, 10),
                          "topic logging is disabled on this daemon", "--logger-memory 0")
            assert await client.logger_status() == dw.LoggerStatus(0, 0, [])

    asyncio.run(main())


@pytest.mark.parametrize(("value", "limit"), [("1G", 1 << 30), ("3m", 3 << 20), ("4096", 4096)])
def test_logger_memory_takes_suffixes(start: Callable[..., Daemon], value: str,
                                      limit: int) -> None:
    daemon = start("--logger-memory", value)

    async def main() -> None:
        async with await daemon.connect() as client:
            assert (await client.logger_status()).memory_limit == limit

    asyncio.run(main())


@pytest.mark.parametrize("value", ["", "12X", "-1", " 1", "+1", "1kk", "k", "1 k",
                                   "99999999999999999999", "17179869184G"])
def test_bad_logger_memory_is_a_usage_error(tmp_path: Path, value: str) -> None:
    key = tmp_path / "key"
    dk.create_key_file(key)
    result = subprocess.run([daemon_exe(), "--port", "0", "--bind", "127.0.0.1", "--key-file",
                             str(key), "--foreground", "--logger-memory", value],
                            capture_output=True, text=True, timeout=WAIT)
    assert result.returncode == 2
    assert result.stderr.startswith("ln_daemon: error: --logger-memory needs a number of bytes")


def test_gaps_are_counted_as_missed(logged: Daemon) -> None:
    ring, tiny = prefix(logged.instance) + "1.1", prefix(logged.instance) + "2.1"
    burst = 3000

    async def main() -> None:
        async with await logged.connect() as client:
            # Sequence numbers the ring never got are missed, exactly.
            await client.ring_create(ring, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await client.logger_topic("box", TOPIC, ring, MD, LAYOUT, SIZE, 100)
            await client.logger_enable("box")
            with Tap(ring, LAYOUT, SIZE) as publisher:
                inject(publisher, [1, 2, 10, 11])
                status = await received(client, "box", 11)
            assert counts(status) == (4, 4, 7, 0, 0)
            # A burst into a ring of 2 slots: the logger may fall behind, but every sample
            # is either received or missed, and every received one stored, skipped or
            # dropped; what is stored is whole and in order.
            await client.ring_create(tiny, "/fast", MD, LAYOUT, SIZE, 2)
            await client.logger_topic("box", "/fast", tiny, MD, LAYOUT, SIZE, 500, divisor=2)
            await client.logger_enable("box")
            with Tap(tiny, LAYOUT, SIZE) as publisher:
                inject(publisher, range(1, burst + 1))
                status = await received(client, "box", burst, "/fast")
            assert status.received == status.stored + status.skipped + status.dropped
            assert status.stored == min(500, status.received - status.skipped)
            chunk = await client.logger_fetch("box", "/fast", 0, 0xFFFFFFFF)
            seqs = [s for s, _, _ in chunk.samples]
            assert len(seqs) == status.stored and seqs == sorted(set(seqs))
            assert all(s % 2 == 0 and d == sample(s) for s, _, d in chunk.samples)
            assert seqs[-1] == burst  # the newest sample stays in the ring until read

    asyncio.run(main())


def test_a_ring_that_appears_later_is_logged_once_it_exists(logged: Daemon) -> None:
    ring = prefix(logged.instance) + "1.1"

    async def main() -> None:
        async with await logged.connect() as client:
            await client.logger_topic("box", TOPIC, ring, MD, LAYOUT, SIZE, 100)
            await client.logger_enable("box")
            status = await topic_status(client, "box")
            assert status.enabled
            assert f"cannot open ring '{ring}': ENOTFOUND" in status.last_error
            await client.ring_create(ring, TOPIC, MD, LAYOUT, SIZE, SLOTS)

            async def opened() -> bool:
                return (await topic_status(client, "box")).last_error == ""

            await until(opened, "the logger to open the ring")
            with Tap(ring, LAYOUT, SIZE) as publisher:
                inject(publisher, range(1, 6))
                await received(client, "box", 5)
            chunk = await client.logger_fetch("box", TOPIC)
            assert [s for s, _, _ in chunk.samples] == [1, 2, 3, 4, 5]
            # A topic of another layout on that ring: the mismatch is its last_error.
            await client.logger_topic("box", "/other", ring, MD, LAYOUT + 1, SIZE, 10)
            other = await topic_status(client, "box", "/other")
            assert other.enabled and "ELAYOUT" in other.last_error
            assert f"hash 0x{LAYOUT:016x}" in other.last_error

    asyncio.run(main())


def test_retarget_keeps_the_data_and_reallocation_clears_it(logged: Daemon) -> None:
    first, second, fresh = (prefix(logged.instance) + n for n in ("1.1", "2.1", "3.1"))

    async def main() -> None:
        async with await logged.connect() as client:
            for name in (first, second, fresh):
                await client.ring_create(name, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await client.logger_topic("box", TOPIC, first, MD, LAYOUT, SIZE, 100)
            await client.logger_enable("box")
            with Tap(first, LAYOUT, SIZE) as publisher:
                inject(publisher, range(1, 4))
                await received(client, "box", 3)
            # The topic's ring moves (same message size and depth): the data stays and the
            # logger reads the new ring.
            await client.logger_topic("box", TOPIC, second, "lntest/renamed", LAYOUT, SIZE, 100)
            status = await topic_status(client, "box")
            assert (status.ring, status.md_name, status.stored, status.enabled) == \
                (second, "lntest/renamed", 3, True)
            with Tap(second, LAYOUT, SIZE) as publisher:
                inject(publisher, range(4, 7))
                status = await received(client, "box", 6)
            assert counts(status) == (6, 6, 0, 0, 0)
            chunk = await client.logger_fetch("box", TOPIC)
            assert [s for s, _, _ in chunk.samples] == [1, 2, 3, 4, 5, 6]
            # Another depth: a new buffer, counters from zero, still enabled.
            await client.logger_topic("box", TOPIC, second, MD, LAYOUT, SIZE, 50)
            status = await topic_status(client, "box")
            assert (status.depth, status.enabled) == (50, True)
            assert counts(status) == (0, 0, 0, 0, 0)
            assert (await client.logger_status()).memory_used == memory(50)
            with Tap(second, LAYOUT, SIZE) as publisher:
                inject(publisher, [7])
                await received(client, "box", 1)
            # A ring whose numbering starts afresh: the buffer keeps rising sequence
            # numbers, so what it held goes (counted as dropped).
            await client.logger_topic("box", TOPIC, fresh, MD, LAYOUT, SIZE, 50)
            with Tap(fresh, LAYOUT, SIZE) as publisher:
                inject(publisher, [1, 2])
                status = await received(client, "box", 3)
            assert counts(status) == (3, 2, 0, 0, 1)
            chunk = await client.logger_fetch("box", TOPIC)
            assert [s for s, _, _ in chunk.samples] == [1, 2]

    asyncio.run(main())


def test_a_grown_ring_is_followed(logged: Daemon) -> None:
    old, successor = prefix(logged.instance) + "1.1", prefix(logged.instance) + "1.2"

    async def main() -> None:
        async with await logged.connect() as client:
            await client.ring_create(old, TOPIC, MD, LAYOUT, SIZE, 4)
            await client.ring_create(successor, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await client.logger_topic("box", TOPIC, old, MD, LAYOUT, SIZE, 100)
            await client.logger_enable("box")
            with Tap(old, LAYOUT, SIZE) as publisher:
                inject(publisher, [1, 2])
                await received(client, "box", 2)
                # The manager grows the topic: the logger's tap moves on with the publisher.
                await client.ring_retire(old, successor)
                inject(publisher, [3, 4])
                await received(client, "box", 4)
            # Told about the new ring, the logger goes on where it is.
            await client.logger_topic("box", TOPIC, successor, MD, LAYOUT, SIZE, 100)
            with Tap(successor, LAYOUT, SIZE) as publisher:
                inject(publisher, [5])
                status = await received(client, "box", 5)
            assert counts(status) == (5, 5, 0, 0, 0) and status.ring == successor
            chunk = await client.logger_fetch("box", TOPIC)
            assert [s for s, _, _ in chunk.samples] == [1, 2, 3, 4, 5]

    asyncio.run(main())


def test_remove_and_unknown_loggers(logged: Daemon) -> None:
    ring = prefix(logged.instance) + "1.1"

    async def main() -> None:
        async with await logged.connect() as client:
            await client.ring_create(ring, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            for topic in ("/a", "/b"):
                await client.logger_topic("box", topic, ring, MD, LAYOUT, SIZE, 10)
            await client.logger_topic("other", "/a", ring, MD, LAYOUT, SIZE, 20)
            await client.logger_enable("box")
            await refused(client.logger_remove("box", "/c"), "logger 'box' has no topic '/c'")
            await client.logger_remove("box", "/a")
            status = await client.logger_status()
            assert [(t.logger, t.topic, t.enabled) for t in status.topics] == \
                [("box", "/b", True), ("other", "/a", False)]
            assert status.memory_used == memory(10) + memory(20)
            await client.logger_remove("box")
            assert [t.logger for t in (await client.logger_status()).topics] == ["other"]
            missing = f"no logger 'box' in instance {logged.instance}"
            await refused(client.logger_remove("box"), missing)
            await refused(client.logger_enable("box"), missing)
            await refused(client.logger_fetch("box", "/b"), missing)
            await refused(client.logger_status("box"), missing)
            await refused(client.logger_fetch("other", "/b"), "logger 'other' has no topic '/b'")
            await client.logger_remove("other", "/a")  # its last topic: the logger goes
            assert await client.logger_status() == dw.LoggerStatus(256 << 20, 0, [])

    asyncio.run(main())


@pytest.mark.parametrize(("change", "text"), [
    ({"logger": ""}, "invalid logger name ''"),
    ({"logger": "a\nb"}, "invalid logger name"),
    ({"topic": ""}, "invalid topic name ''"),
    ({"ring": "/ln.someone_else.1.1"}, "is not in the namespace of instance"),
    ({"message_size": 0}, f"message size 0 out of range 1..{MAX_LOGGED}"),
    ({"depth": 0}, "depth must be at least 1"),
    ({"divisor": 0}, "divisor must be at least 1"),
    ({"span": -1.0}, "span must be 0 (none) or a number of seconds"),
    ({"span": math.nan}, "span must be 0 (none) or a number of seconds"),
    ({"span": math.inf}, "span must be 0 (none) or a number of seconds"),
    ({"depth": 0xFFFFFFFF, "message_size": MAX_LOGGED}, "raise the limit with ln_daemon "
     "--logger-memory"),
])
def test_invalid_logger_topics_are_refused(logged: Daemon, change: dict[str, object],
                                           text: str) -> None:
    args: dict[str, object] = {"logger": "box", "topic": TOPIC,
                               "ring": prefix(logged.instance) + "1.1", "md_name": MD,
                               "layout_hash": LAYOUT, "message_size": SIZE, "depth": 10,
                               "divisor": 1, "span": 0.0}
    args.update(change)

    async def main() -> None:
        async with await logged.connect() as client:
            await refused(client.logger_topic(**args), text)  # type: ignore[arg-type]
            assert (await client.logger_status()).topics == []

    asyncio.run(main())


def test_instances_are_separate(logged: Daemon) -> None:
    other = unique_instance()
    mine, theirs = prefix(logged.instance) + "1.1", prefix(other) + "1.1"

    async def main() -> None:
        async with await logged.connect() as client, await logged.connect(other) as stranger:
            await client.ring_create(mine, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await stranger.ring_create(theirs, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await client.logger_topic("box", TOPIC, mine, MD, LAYOUT, SIZE, 10)
            await client.logger_enable("box")
            # The other instance sees none of it and cannot touch it or its ring...
            status = await stranger.logger_status()
            assert status.topics == [] and status.memory_used == memory(10)
            missing = f"no logger 'box' in instance {other}"
            await refused(stranger.logger_fetch("box", TOPIC), missing)
            await refused(stranger.logger_enable("box", enable=False), missing)
            await refused(stranger.logger_remove("box"), missing)
            await refused(stranger.logger_topic("spy", TOPIC, mine, MD, LAYOUT, SIZE, 10),
                          "not in the namespace")
            # ...and a logger of the same name there is another logger.
            await stranger.logger_topic("box", TOPIC, theirs, MD, LAYOUT, SIZE, 20)
            with Tap(mine, LAYOUT, SIZE) as publisher:
                inject(publisher, [1, 2])
                await received(client, "box", 2)
            assert (await topic_status(stranger, "box")).received == 0
            await stranger.logger_remove("box")
            assert [t.depth for t in (await client.logger_status()).topics] == [10]

    try:
        asyncio.run(main())
    finally:
        purge(other)


def _topic_payload(ring: str, tail: bytes = b"") -> bytes:
    return (wc.encode_str("box") + wc.encode_str(TOPIC) + wc.encode_str(ring) + wc.encode_str(MD)
            + struct.pack("<QQIId", LAYOUT, SIZE, 10, 1, 0.0) + tail)


MALFORMED = {
    "truncated LOGGER_TOPIC": (dw.Msg.LOGGER_TOPIC, lambda n: _topic_payload(n)[:-1]),
    "LOGGER_TOPIC with trailing bytes": (dw.Msg.LOGGER_TOPIC, lambda n: _topic_payload(n, b"\0")),
    "LOGGER_TOPIC with an overlong ring": (dw.Msg.LOGGER_TOPIC,
                                           lambda n: _topic_payload(n + "x" * 300)),
    "LOGGER_REMOVE without a topic": (dw.Msg.LOGGER_REMOVE, lambda n: wc.encode_str("box")),
    "LOGGER_ENABLE with enable 2": (dw.Msg.LOGGER_ENABLE,
                                    lambda n: wc.encode_str("box") + struct.pack("<BB", 2, 0)),
    "LOGGER_ENABLE with clear 7": (dw.Msg.LOGGER_ENABLE,
                                   lambda n: wc.encode_str("box") + struct.pack("<BB", 1, 7)),
    "LOGGER_FETCH without max_bytes": (dw.Msg.LOGGER_FETCH, lambda n: wc.encode_str("box")
                                       + wc.encode_str(TOPIC) + struct.pack("<Q", 0)),
    "LOGGER_STATUS of an overlong name": (dw.Msg.LOGGER_STATUS, lambda n: wc.encode_str("x" * 256)),
    "LOGGER_STATUS with a huge length": (dw.Msg.LOGGER_STATUS,
                                         lambda n: struct.pack("<I", 0xFFFFFFFF)),
}


@pytest.mark.parametrize("case", sorted(MALFORMED))
def test_malformed_requests_close_only_their_connection(logged: Daemon, case: str) -> None:
    mtype, payload = MALFORMED[case]
    ring = prefix(logged.instance) + "1.1"

    async def main() -> None:
        async with await logged.connect() as client:
            await client.ring_create(ring, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await client.logger_topic("box", TOPIC, ring, MD, LAYOUT, SIZE, 10)
            await client.logger_enable("box")
            raw = RawConnection(logged.port)
            try:
                raw.authenticate(logged.key, logged.instance)
                raw.send(raw.frame(mtype, 7, payload(ring)))
                code, text = await asyncio.to_thread(raw.expect_error_and_close)
            finally:
                raw.close()
            assert code == dw.ErrorCode.BAD_REQUEST
            assert text == f"malformed {mtype.name} request"
            # The other connection and the logger carry on, unchanged.
            with Tap(ring, LAYOUT, SIZE) as publisher:
                inject(publisher, [1, 2, 3])
                status = await received(client, "box", 3)
            assert (status.depth, status.stored) == (10, 3)

    asyncio.run(main())


PUBLISHER = """
import struct, sys
sys.path.insert(0, sys.argv[1])
from ringtap import Tap
ring, layout, size = sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
with Tap(ring, layout, size) as tap:
    seq = 0
    while True:
        seq += 1
        tap.inject(struct.pack("<Q", seq).ljust(size, b"\\xcd"), seq, seq)
        if seq == 1:
            print("publishing", flush=True)
"""


def test_publisher_killed_while_logged(logged: Daemon) -> None:
    ring = prefix(logged.instance) + "1.1"

    async def main() -> None:
        async with await logged.connect() as client:
            await client.ring_create(ring, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            await client.logger_topic("box", TOPIC, ring, MD, LAYOUT, SIZE, 100_000)
            await client.logger_enable("box")
            publisher = subprocess.Popen([sys.executable, "-c", PUBLISHER, str(HERE), ring,
                                          str(LAYOUT), str(SIZE)], stdout=subprocess.PIPE)
            logged.extra.append(publisher)
            assert publisher.stdout is not None
            assert publisher.stdout.readline() == b"publishing\n"

            async def busy() -> bool:
                return (await topic_status(client, "box")).received >= 1000

            await until(busy, "the logger to take 1000 samples")
            publisher.send_signal(signal.SIGKILL)
            assert publisher.wait(WAIT) == -signal.SIGKILL
            published = await client.ring_write_seq(ring)
            status = await received(client, "box", published)
            assert status.received == status.stored + status.dropped
            assert status.last_error == ""
            got: list[int] = []
            after = 0
            while chunk := (await client.logger_fetch("box", TOPIC, after)).samples:
                assert all(d == sample(s) for s, _, d in chunk)  # none torn
                got += [s for s, _, _ in chunk]
                after = chunk[-1][0]
            assert len(got) == status.stored and got == sorted(set(got)) and got[-1] == published
            await client.ping()
            await client.logger_enable("box", enable=False)
            await client.logger_remove("box")

    asyncio.run(main())


def test_shutdown_joins_the_logger_threads(logged: Daemon) -> None:
    ring = prefix(logged.instance) + "1.1"

    async def main() -> None:
        async with await logged.connect() as client:
            await client.ring_create(ring, TOPIC, MD, LAYOUT, SIZE, SLOTS)
            for topic in ("/a", "/b", "/c"):
                await client.logger_topic("box", topic, ring, MD, LAYOUT, SIZE, 10)
            await client.logger_enable("box")

    asyncio.run(main())
    assert stop_daemon(logged) == []  # SIGTERM: exit status 0
    assert "stopped 3 logger thread(s)" in logged.log_text()
