"""Resource samples in the scheduler (processes/resources.py, docs/process_management.md
"Resources and limits"): the newest sample per process in `status`, a sample of a daemon
replacing that daemon's earlier ones, `max_rss`/`max_cpu` flagging a process (and with
`on_limit: restart` restarting it), the flag gone with a sample within the limits; on the
fake daemon, samples put into its event queue as ln_daemon's client would."""

from __future__ import annotations

from collections.abc import AsyncIterator

import pytest

from links_and_nodes.manager.config import model
from links_and_nodes.manager.processes.daemon_resources import (
    HostSample,
    ProcessSample,
    ResourceSample,
)
from links_and_nodes.manager.processes.resources import Resources, limit_problem
from links_and_nodes.manager.processes.states import ProcState as S

from .test_scheduler import LIMIT, World, make, proc, until

MIB = 1 << 20


@pytest.fixture
async def worlds() -> AsyncIterator[list[World]]:
    made: list[World] = []
    yield made
    for w in made:
        await w.sched.close()
        await w.daemon.kill_all()


def host(name: str = "robot") -> HostSample:
    return HostSample(host=name, time=1.0, load=(0.5, 0.4, 0.3), cpu=10.0, cpus=[10.0, 10.0],
                      mem_total=8 << 30, mem_available=4 << 30, swap_total=0, swap_free=0)


def sample(name: str, pid: int, rss: int = 10 * MIB, cpu: float | None = 5.0) -> ProcessSample:
    return ProcessSample(name, pid, cpu, rss, 3, 10, 2, 5)


def feed(w: World, *procs: ProcessSample) -> None:
    w.daemon.queue.put_nowait(ResourceSample(host(), list(procs)))


def test_limit_problem_and_book() -> None:
    cfg = model.Process(name="p", location=model.Location("x.lnc", 1, 1), command="p",
                        max_rss=100 * MIB, max_cpu=150.0)
    assert limit_problem(cfg, sample("p", 1, rss=99 * MIB, cpu=149.0)) == ""
    assert limit_problem(cfg, sample("p", 1, rss=101 * MIB, cpu=None)) == \
        "RSS 101.0 MiB > max_rss 100.0 MiB"
    assert limit_problem(cfg, sample("p", 1, rss=1, cpu=151.0)) == "CPU 151 % > max_cpu 150 %"
    book = Resources()
    book.take(ResourceSample(host("a"), [sample("x", 1), sample("y", 2)]), source=1)
    book.take(ResourceSample(host("b"), [sample("z", 3)]), source=2)
    book.take(ResourceSample(host("a"), [sample("y", 2, rss=7)]), source=1)  # x is gone
    assert sorted(book.processes) == ["y", "z"] and book.processes["y"].rss == 7
    assert book.process("y", 2) is not None and book.process("y", 99) is None
    assert book.process_fields("x", 1)["rss"] is None
    signals = book.signals()
    assert signals["process/y/rss"] == 7.0 and signals["host/b/load1"] == 0.5
    assert signals["host/a/mem_used"] == float(4 << 30)
    assert [h["host"] for h in book.host_listing()] == ["a", "b"]


async def test_status_shows_the_newest_sample(worlds: list[World]) -> None:
    w = make(worlds, proc("a"))
    w.sched.start("a")
    await w.sched.wait_ready("a", LIMIT)
    pid = w.sched.procs["a"].pid
    assert pid is not None
    feed(w, sample("a", pid, rss=42 * MIB, cpu=12.5))
    await until(lambda: w.sched.status()[0]["rss"] == 42 * MIB)
    row = w.sched.status()[0]
    assert (row["cpu"], row["threads"], row["fds"], row["limit"]) == (12.5, 3, 5, "")
    feed(w, sample("a", pid + 100000))  # another run's pid: not this run's figures
    await until(lambda: w.sched.status()[0]["rss"] is None)


async def test_max_rss_warns_and_clears(worlds: list[World]) -> None:
    w = make(worlds, proc("a", max_rss=16 * MIB))
    w.sched.start("a")
    await w.sched.wait_ready("a", LIMIT)
    pid = w.sched.procs["a"].pid
    assert pid is not None
    feed(w, sample("a", pid, rss=32 * MIB))
    await until(lambda: w.sched.procs["a"].limit != "")
    assert w.sched.procs["a"].limit == "RSS 32.0 MiB > max_rss 16.0 MiB"
    assert w.sched.procs["a"].state == S.READY  # only flagged
    feed(w, sample("a", pid, rss=8 * MIB))
    await until(lambda: w.sched.procs["a"].limit == "")
    assert w.sched.procs["a"].state == S.READY


async def test_max_cpu_with_on_limit_restart(worlds: list[World]) -> None:
    w = make(worlds, proc("a", max_cpu=50.0, on_limit=model.OnLimit.RESTART,
                                 restart_delay=0.01))
    w.sched.start("a")
    await w.sched.wait_ready("a", LIMIT)
    pid = w.sched.procs["a"].pid
    assert pid is not None
    feed(w, sample("a", pid, cpu=99.0))
    await until(lambda: w.daemon.spawned.count("a") >= 2)
    await w.sched.wait_ready("a", LIMIT)
    failed = [t for t in w.sched.history("a") if t.state == S.FAILED]
    assert failed and failed[0].reason.startswith("over its limit: CPU 99 % > max_cpu 50 %")
    assert w.sched.procs["a"].limit == ""  # a new run
