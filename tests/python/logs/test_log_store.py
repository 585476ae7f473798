"""The manager's log store (manager/registry/logs.py) on its own: LOG batches parsed or
refused whole with the entry and what is wrong, the ring dropping its oldest lines with a
count, the filters of `log`, `since` and waiting for the next line."""

from __future__ import annotations

import asyncio

import pytest

from links_and_nodes.manager.registry.logs import (
    END,
    FIELD,
    LogBatchError,
    LogFilter,
    LogStore,
    level_number,
    parse_batch,
)


def entry(level: int, text: str, file: str = "a.c", line: int = 1, t: int = 5) -> str:
    return FIELD.join([str(level), str(t), file, str(line), "", text]) + END


def test_a_batch_is_parsed_or_refused_whole() -> None:
    assert parse_batch(2, entry(30, "x") + entry(40, f"y{FIELD}z")) == [
        (30, 5, "a.c", 1, "", "x"), (40, 5, "a.c", 1, "", f"y{FIELD}z")]
    store = LogStore()
    for count, text, why in [
            (2, entry(30, "x"), "count is 2 but the entries text holds 1"),
            (1, entry(30, "x")[:-1], "do not end with LOG_END"),
            (1, "30" + FIELD + "5" + END, "entry 0: 2 fields, expected 6"),
            (1, entry(70, "x"), "entry 0: unknown log level 70"),
            (1, entry(30, "x").replace("5", "five", 1), "entry 0: invalid literal")]:
        with pytest.raises(LogBatchError, match=why):
            store.add_batch("c", "h", 1, 0, count, text)
    assert store.query(LogFilter()) == [] and store.last_seq == 0


def test_the_ring_drops_its_oldest_lines_and_counts_them() -> None:
    store = LogStore(capacity=3)
    store.add_batch("c", "h", 7, 2, 5, "".join(entry(20, str(i)) for i in range(5)))
    assert [e.text for e in store.query(LogFilter())] == ["2", "3", "4"]
    assert store.evicted == 2 and store.last_seq == 5
    assert store.drops() == [{"client": "c", "host": "h", "dropped": 2}]
    assert [e.text for e in store.query(LogFilter(), since=4)] == ["4"]  # seq 5
    assert [e.text for e in store.query(LogFilter(), since=1)] == ["2", "3", "4"]
    assert [e.text for e in store.query(LogFilter(), n=1)] == ["4"]
    assert store.query(LogFilter(), n=0) == []


def test_filters() -> None:
    store = LogStore()
    store.add(time_ns=1, level=10, source="client", client="arm_ctl", host="robot1",
              text="Debug detail")
    store.add(time_ns=2, level=40, source="output", client="planner", process="planner",
              host="robot2", text="No path found")
    store.process_of = lambda host, pid: "arm/controller" if pid == 9 else ""
    store.add(time_ns=3, level=30, source="client", client="ctl", host="robot1", pid=9,
              text="joint hot")

    def texts(f: LogFilter) -> list[str]:
        return [e.text for e in store.query(f)]

    assert texts(LogFilter(level=30)) == ["No path found", "joint hot"]
    assert texts(LogFilter(process="arm/*")) == ["joint hot"]
    assert texts(LogFilter(process="arm_ctl")) == ["Debug detail"]
    assert texts(LogFilter(host="robot2")) == ["No path found"]
    assert texts(LogFilter(grep="NO PATH")) == ["No path found"]
    assert texts(LogFilter(level=50)) == []


def test_level_names() -> None:
    assert [level_number(x) for x in ("debug", "WARN", "fatal", "err", 40, "30")] == \
        [10, 30, 50, 40, 40, 30]
    for bad in ("loud", 5, 60, ""):
        with pytest.raises(ValueError, match="unknown log level"):
            level_number(bad)


def test_wait_returns_on_the_next_line_or_after_the_timeout() -> None:
    async def run() -> None:
        store = LogStore()
        await store.wait(0, 0.05)  # nothing came: back after the timeout
        waiter = asyncio.create_task(store.wait(0, 60))
        await asyncio.sleep(0)
        store.add(time_ns=1, level=20, source="client", client="c", host="h", text="x")
        await asyncio.wait_for(waiter, 60)  # an upper bound, not a measurement

    asyncio.run(run())
