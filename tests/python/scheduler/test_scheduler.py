"""The scheduler's rules on a fake daemon: dependency order for chains and diamonds
(asserted from the recorded transitions, never from timing), readiness gates, start_before,
states, failures, restart back-off and its limit, the rate watchdog, and stopping dependents
first."""

from __future__ import annotations

import asyncio
import os
import signal
import sys
import time
from collections.abc import AsyncIterator, Callable
from pathlib import Path
from types import SimpleNamespace

import pytest

from links_and_nodes.manager.config import model
from links_and_nodes.manager.processes.scheduler import Backend, Scheduler, StartError, Transition
from links_and_nodes.manager.processes.states import ProcState as S

from .fake_daemon import (
    Exit,
    FakeDaemon,
    FakeError,
    FakeRegistry,
    Info,
    Line,
    Spec,
    backend,
)

LIMIT = 60.0
HERE = model.Location("test.lnc", 1, 1)
PY = sys.executable


def proc(name: str, command: str = "sleep 60", **kw: object) -> model.Process:
    return model.Process(name=name, location=HERE, command=command, **kw)  # type: ignore[arg-type]


def config(*procs: model.Process, states: tuple[model.State, ...] = (),
           groups: tuple[model.Group, ...] = ()) -> model.Config:
    return model.Config(files=["test.lnc"], instance=model.Instance("t", ":1", HERE),
                        processes={p.name: p for p in procs},
                        states={s.name: s for s in states},
                        groups={g.name: g for g in groups})


class World:
    def __init__(self, cfg: model.Config, daemon: FakeDaemon | None = None) -> None:
        self.daemon = daemon or FakeDaemon()
        self.registry = FakeRegistry()
        self.sched = Scheduler(cfg, self.registry, backend(self.daemon),
                               manager_address="127.0.0.1:1")
        self.log: list[tuple[str, S]] = []
        self.sched.transition_listeners.append(lambda n, t: self.log.append((n, t.state)))

    def index(self, name: str, state: S) -> int:
        return self.log.index((name, state))


@pytest.fixture
async def world_factory() -> AsyncIterator[list[World]]:
    worlds: list[World] = []
    yield worlds
    for w in worlds:
        await w.sched.close()
        await w.daemon.kill_all()


async def until(predicate: Callable[[], bool]) -> None:
    """Poll `predicate` (an upper bound of LIMIT seconds, not a measurement)."""
    async with asyncio.timeout(LIMIT):
        while not predicate():
            await asyncio.sleep(0.01)


def make(worlds: list[World], *procs: model.Process, **kw: object) -> World:
    w = World(config(*procs, **kw))  # type: ignore[arg-type]
    worlds.append(w)
    return w


async def test_chain_starts_in_dependency_order(world_factory: list[World]) -> None:
    w = make(world_factory, proc("c", depends_on=["b"]), proc("b", depends_on=["a"]), proc("a"))
    w.sched.start("c")
    await w.sched.wait_ready("all", LIMIT)
    assert w.daemon.spawned == ["a", "b", "c"]
    assert w.index("a", S.READY) < w.index("b", S.READY) < w.index("c", S.READY)


async def test_diamond_starts_shared_dependency_once(world_factory: list[World]) -> None:
    w = make(world_factory, proc("a"), proc("b", depends_on=["a"]), proc("c", depends_on=["a"]),
             proc("d", depends_on=["b", "c"]))
    w.sched.start("d")
    await w.sched.wait_ready("all", LIMIT)
    assert w.daemon.spawned.count("a") == 1 and w.daemon.spawned[0] == "a"
    assert w.daemon.spawned[-1] == "d"
    ready_d = w.index("d", S.READY)
    assert w.index("b", S.READY) < ready_d and w.index("c", S.READY) < ready_d
    assert w.index("a", S.READY) < min(w.index("b", S.STARTING) + 10**6,
                                       w.index("b", S.READY))


async def test_ready_regex_gates_dependents(world_factory: list[World],
                                            tmp_path: Path) -> None:
    gate = tmp_path / "go"
    script = tmp_path / "sensor.py"
    script.write_text(f"import os, time\nprint('init', flush=True)\n"
                      f"while not os.path.exists({str(gate)!r}): time.sleep(0.01)\n"
                      f"print('sensor READY now', flush=True)\ntime.sleep(60)\n")
    w = make(world_factory, proc("sensor", f"{PY} {script}", ready_regex=r"READY"),
             proc("ctrl", depends_on=["sensor"]))
    w.sched.start("ctrl")
    await w.sched.wait(["sensor"], {S.STARTED}, LIMIT)
    await until(lambda: any(line.text == "init" for line in w.sched.output("sensor")))
    assert w.daemon.spawned == ["sensor"]  # its output came, the regex did not match yet
    assert w.sched.procs["ctrl"].state == S.STARTING
    gate.touch()
    await w.sched.wait_ready("all", LIMIT)
    assert w.daemon.spawned == ["sensor", "ctrl"]
    assert "READY" in w.sched.procs["sensor"].reason


class OutputFirstDaemon(FakeDaemon):
    """Answers SPAWN only after the scheduler took the new process's first output line off
    the event queue: the order a busy manager can see with the real daemon."""

    async def spawn(self, spec: Spec) -> Info:
        info = await super().spawn(spec)
        p = self.procs[spec.name]
        async with asyncio.timeout(LIMIT):
            while not p.lines or not self.queue.empty():
                await asyncio.sleep(0.005)
        await asyncio.sleep(0)  # the pump handles the line it took
        return info


async def test_ready_line_before_spawn_answer_counts(world_factory: list[World]) -> None:
    say_ready = "sh -c 'echo ready; exec sleep 60'"
    w = World(config(proc("a", say_ready, ready_regex="^ready"),
                     proc("b", say_ready, ready_regex="^ready", depends_on=["a"])),
              OutputFirstDaemon())
    world_factory.append(w)
    w.sched.start("all")
    await w.sched.wait_ready("all", 10)
    assert w.daemon.spawned == ["a", "b"]


async def test_ready_on_topic_and_service(world_factory: list[World]) -> None:
    w = make(world_factory, proc("pub", ready_on_topic="arm.state"),
             proc("prov", ready_on_service="arm.set_gains"),
             proc("user", depends_on=["pub", "prov"]))
    w.sched.start("user")
    await w.sched.wait(["pub", "prov"], {S.STARTED}, LIMIT)
    w.registry.publishers["arm.state"] = 1
    w.registry.changed()
    await w.sched.wait(["pub"], {S.READY}, LIMIT)
    assert w.sched.procs["prov"].state == S.STARTED and "user" not in w.daemon.spawned
    w.registry.services.add("arm.set_gains")
    w.registry.changed()
    await w.sched.wait_ready("all", LIMIT)
    assert w.index("prov", S.READY) < w.index("user", S.READY)


async def test_start_before_runs_to_completion_first(world_factory: list[World]) -> None:
    w = make(world_factory, proc("setup", "sh -c 'echo prepared'"),
             proc("main", start_before=["setup"]))
    w.sched.start("main")
    await w.sched.wait_ready("main", LIMIT)
    assert w.index("setup", S.FINISHED) < w.index("main", S.READY)


async def test_failed_dependency_fails_dependent(world_factory: list[World]) -> None:
    w = make(world_factory, proc("a"), proc("b", depends_on=["a"]))
    w.daemon.fail_spawn.add("a")
    w.sched.start("b")
    with pytest.raises(StartError, match="command not found"):
        await w.sched.wait_ready("b", LIMIT)
    await w.sched.wait(["b"], {S.FAILED}, LIMIT)
    assert "dependency a did not become ready" in w.sched.procs["b"].reason
    assert "b" not in w.daemon.spawned


async def test_state_brought_up_before_dependent(world_factory: list[World],
                                                 tmp_path: Path) -> None:
    flag = tmp_path / "flag"
    st = model.State("net", HERE, check=f"test -e {flag}", up=f"touch {flag}")
    w = make(world_factory, proc("user", depends_on=["net"]), states=(st,))
    w.sched.start("user")
    await w.sched.wait_ready("user", LIMIT)
    assert flag.exists()
    assert w.sched.states["net"].up is True


async def test_crash_restarts_with_backoff_then_gives_up(world_factory: list[World]) -> None:
    w = make(world_factory, proc("crasher", "sh -c 'exit 3'", restart=model.Restart.ON_FAILURE,
                                 restart_limit=2, restart_delay=0.01))
    w.sched.start("crasher")
    rt = w.sched.procs["crasher"]
    await until(lambda: "gave up" in rt.reason)
    assert w.daemon.spawned == ["crasher"] * 3
    assert rt.state == S.FAILED and "gave up after 2 restarts" in rt.reason
    assert "exit status 3" in rt.reason


async def test_successful_exit_is_finished_not_restarted(world_factory: list[World]) -> None:
    w = make(world_factory, proc("once", "true", restart=model.Restart.ON_FAILURE))
    w.sched.start("once")
    await w.sched.wait(["once"], {S.FINISHED}, LIMIT)
    await asyncio.sleep(0.05)
    assert w.daemon.spawned == ["once"]


async def test_watchdog_restarts_stalled_publisher(world_factory: list[World]) -> None:
    w = make(world_factory, proc("pub", watchdog=model.Watchdog("arm.state", 100.0),
                                 restart_delay=0.01))
    w.sched.start("pub")
    await w.sched.wait_ready("pub", LIMIT)
    # nothing is published: the watchdog window (1 s) passes with rate 0
    await until(lambda: w.daemon.spawned.count("pub") >= 2)
    await w.sched.wait_ready("pub", LIMIT)
    assert "watchdog: arm.state at 0 Hz < 100 Hz" in [t.reason for t in
                                                      w.sched.history("pub")
                                                      if t.state == S.STOPPING][0]


async def test_stop_stops_dependents_first(world_factory: list[World]) -> None:
    w = make(world_factory, proc("a"), proc("b", depends_on=["a"]), proc("c", depends_on=["b"]))
    w.sched.start("c")
    await w.sched.wait_ready("all", LIMIT)
    await w.sched.stop("a")
    assert all(w.sched.procs[n].state == S.STOPPED for n in "abc")
    assert w.index("c", S.STOPPED) < w.index("b", S.STOPPING)
    assert w.index("b", S.STOPPED) < w.index("a", S.STOPPING)


async def test_lost_dependency_stops_and_restores_dependent(world_factory: list[World],
                                                            tmp_path: Path) -> None:
    marker = tmp_path / "crashed-once"
    a_cmd = f"sh -c 'if [ -e {marker} ]; then sleep 60; else touch {marker}; sleep 0.2; exit 1; fi'"
    w = make(world_factory, proc("a", a_cmd, restart=model.Restart.ON_FAILURE,
                                 restart_delay=0.01),
             proc("b", depends_on=["a"]))
    w.sched.start("b")
    await w.sched.wait_ready("all", LIMIT)
    await w.sched.wait(["a"], {S.FAILED}, LIMIT)
    await until(lambda: w.daemon.spawned == ["a", "b", "a", "b"])
    await w.sched.wait(["a", "b"], {S.READY}, LIMIT)
    assert w.index("a", S.FAILED) < w.index("b", S.STOPPING)
    assert [state for name, state in w.log if name == "b"][-3:] == [S.STOPPED, S.STARTING,
                                                                     S.READY]


async def test_groups_and_all(world_factory: list[World]) -> None:
    g = model.Group("arm", HERE, members=["a", "b"])
    w = make(world_factory, proc("a"), proc("b"), proc("c"), groups=(g,))
    assert w.sched.start("arm") == ["a", "b"]
    await w.sched.wait_ready("arm", LIMIT)
    assert w.sched.procs["c"].state == S.STOPPED
    await w.sched.stop("all")
    with pytest.raises(KeyError):
        w.sched.targets("nothing")


async def test_start_rate_limit_spaces_starts(monkeypatch: pytest.MonkeyPatch) -> None:
    """Five starts at 20/s on a frozen clock: each waits 50 ms longer than the one before."""
    from links_and_nodes.manager.processes import spawning as sched_mod

    slept: list[float] = []

    async def fake_sleep(delay: float) -> None:
        slept.append(round(delay, 6))

    monkeypatch.setattr(sched_mod.time, "monotonic", lambda: 100.0)
    monkeypatch.setattr(sched_mod.asyncio, "sleep", fake_sleep)
    limiter = sched_mod.RateLimiter(20.0)
    for _ in range(5):
        await limiter.acquire()
    assert slept == [0.05, 0.1, 0.15, 0.2]
    unlimited = sched_mod.RateLimiter(None)
    await unlimited.acquire()
    assert len(slept) == 4


async def test_disable_stop_refused_unless_forced(world_factory: list[World]) -> None:
    w = make(world_factory, proc("keep", flags={"disable_stop"}))
    w.sched.start("keep")
    await w.sched.wait_ready("keep", LIMIT)
    with pytest.raises(StartError, match="disable_stop"):
        await w.sched.stop("keep")
    assert w.sched.procs["keep"].state == S.READY
    await w.sched.stop("keep", force=True)
    assert w.sched.procs["keep"].state == S.STOPPED


async def test_reload_adds_changes_and_removes(world_factory: list[World]) -> None:
    w = make(world_factory, proc("a"), proc("b"))
    w.sched.start("a")
    await w.sched.wait_ready("a", LIMIT)
    result = w.sched.apply_config(config(proc("a", "sleep 61"), proc("c")))
    assert result == {"added": ["c"], "removed": ["b"], "changed": ["a"],
                      "removed_when_stopped": []}
    assert w.sched.procs["a"].state == S.READY  # running on with its old command
    await w.sched.restart("a")
    assert w.sched.procs["a"].cfg.command == "sleep 61"
    w.sched.start("c")
    await w.sched.wait_ready("all", LIMIT)


async def test_output_and_exit_before_the_spawn_answer(world_factory: list[World]) -> None:
    """The daemon's events may overtake its answer to SPAWN; none of them may be lost."""
    w = make(world_factory, proc("quick", "sh -c 'echo go; exit 4'"),
             proc("gated", "sh -c 'echo go; sleep 60'", ready_regex="go"))
    w.daemon.late_answer |= {"quick", "gated"}
    w.sched.start("quick")
    await w.sched.wait(["quick"], {S.FAILED}, LIMIT)
    assert w.sched.procs["quick"].reason == "exit status 4"
    w.sched.start("gated")
    await w.sched.wait_ready("gated", LIMIT)


async def test_old_ready_period_does_not_reset_the_restart_count(
        world_factory: list[World], tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """"Stayed ready for 10 s" is about the run that just ended: a process that was ready
    once and then keeps failing before it gets ready again still gives up.  The scheduler's
    monotonic clock is the test's: every failure advances it by 6 s."""
    from links_and_nodes.manager.processes import managed

    now = [0.0]
    monkeypatch.setattr(managed, "time",
                        SimpleNamespace(time=time.time, monotonic=lambda: now[0]))
    marker, gate = tmp_path / "ran", tmp_path / "gate"
    cmd = (f"sh -c 'if [ -e {marker} ]; then exit 1; fi; touch {marker}; echo up; "
           f"while [ ! -e {gate} ]; do sleep 0.01; done; exit 1'")
    w = make(world_factory, proc("p", cmd, ready_regex="^up", restart=model.Restart.ON_FAILURE,
                                 restart_limit=2, restart_delay=0.01))

    def advance(name: str, t: Transition) -> None:
        if t.state == S.FAILED:
            now[0] += 6.0
    w.sched.transition_listeners.append(advance)
    w.sched.start("p")
    await w.sched.wait_ready("p", LIMIT)  # ready at 0 s
    gate.touch()  # fails at 6 s, then before being ready at 12 s, 18 s, ...
    rt = w.sched.procs["p"]
    await until(lambda: "gave up" in rt.reason or w.daemon.spawned.count("p") > 3)
    assert w.daemon.spawned == ["p"] * 3
    assert "gave up after 2 restarts" in rt.reason


def crash_once(tmp_path: Path, gate: Path) -> str:
    """A command that runs until `gate` exists and then fails, the first time; after that
    it just runs."""
    marker = tmp_path / f"{gate.name}-ran"
    return (f"sh -c 'if [ -e {marker} ]; then exec sleep 60; fi; touch {marker}; "
            f"while [ ! -e {gate} ]; do sleep 0.01; done; exit 1'")


def slow_to_stop(tmp_path: Path, gate: Path) -> str:
    """A command that, sent SIGTERM, exits only once `gate` exists."""
    script = tmp_path / f"{gate.name}.py"
    script.write_text(f"import os, signal, time\n"
                      f"def term(*_):\n"
                      f"    while not os.path.exists({str(gate)!r}): time.sleep(0.01)\n"
                      f"    raise SystemExit(0)\n"
                      f"signal.signal(signal.SIGTERM, term)\n"
                      f"print('up', flush=True)\n"
                      f"while True: time.sleep(1)\n")
    return f"{PY} {script}"


async def test_stopped_dependent_stays_stopped_when_its_dependency_returns(
        world_factory: list[World], tmp_path: Path) -> None:
    """A dependent stopped because its dependency went down comes back with it, unless it
    was stopped on request meanwhile."""
    gate = tmp_path / "crash"
    w = make(world_factory, proc("a", crash_once(tmp_path, gate)),
             proc("b", depends_on=["a"]))
    w.sched.start("b")
    await w.sched.wait_ready("all", LIMIT)
    gate.touch()
    await w.sched.wait(["a", "b"], {S.FAILED, S.STOPPED}, LIMIT)
    await w.sched.stop("b")
    w.sched.start("a")
    await w.sched.wait_ready("a", LIMIT)
    assert w.sched.procs["b"].state == S.STOPPED
    assert w.daemon.spawned == ["a", "b", "a"]


async def test_stop_request_during_a_dependency_loss_stop_returns(
        world_factory: list[World], tmp_path: Path) -> None:
    """`stop b` while b is being stopped because its dependency crashed: b stays stopped
    even though the dependency is ready again by then, and the stop returns."""
    crash, release = tmp_path / "crash", tmp_path / "release"
    w = make(world_factory, proc("a", crash_once(tmp_path, crash),
                                 restart=model.Restart.ON_FAILURE, restart_delay=0.01),
             proc("b", slow_to_stop(tmp_path, release), depends_on=["a"],
                  ready_regex="^up", term_timeout=LIMIT))
    w.sched.start("b")
    await w.sched.wait_ready("all", LIMIT)
    crash.touch()
    await w.sched.wait(["b"], {S.STOPPING}, LIMIT)
    stopping = asyncio.create_task(w.sched.stop("b"))
    await until(lambda: w.daemon.spawned.count("a") == 2)
    await w.sched.wait(["a"], {S.READY}, LIMIT)
    release.touch()
    await until(lambda: stopping.done() or w.daemon.spawned.count("b") > 1)
    assert w.daemon.spawned.count("b") == 1 and w.sched.procs["b"].state == S.STOPPED
    assert await stopping == ["b"]


async def test_lost_dependency_restores_the_whole_chain(world_factory: list[World],
                                                        tmp_path: Path) -> None:
    """a <- b <- c: when a crashes both b and c are stopped, and both come back with a."""
    gate = tmp_path / "crash"
    w = make(world_factory, proc("a", crash_once(tmp_path, gate),
                                 restart=model.Restart.ON_FAILURE, restart_delay=0.01),
             proc("b", depends_on=["a"]), proc("c", depends_on=["b"]))
    w.sched.start("c")
    await w.sched.wait_ready("all", LIMIT)
    gate.touch()
    await until(lambda: w.daemon.spawned.count("b") == 2)
    await w.sched.wait(["b"], {S.READY}, LIMIT)
    assert w.sched.procs["c"].state != S.STOPPED  # started as soon as b was ready
    await w.sched.wait_ready("all", LIMIT)
    assert w.daemon.spawned == ["a", "b", "c", "a", "b", "c"]


class BrokenSpawnDaemon(FakeDaemon):
    """Its SPAWN fails with an exception that is not the backend's error type (as a
    spawn spec the client cannot encode would)."""

    async def spawn(self, spec: Spec) -> Info:
        raise UnicodeEncodeError("utf-8", "\udcff", 0, 1, "surrogates not allowed")


async def test_unexpected_start_error_fails_the_process(world_factory: list[World]) -> None:
    w = World(config(proc("a"), proc("b", depends_on=["a"])), BrokenSpawnDaemon())
    world_factory.append(w)
    w.sched.start("b")
    tasks = [w.sched.procs[n].task for n in "ab"]
    await asyncio.wait([t for t in tasks if t is not None], timeout=LIMIT)
    assert [w.sched.procs[n].state for n in "ab"] == [S.FAILED, S.FAILED]
    assert "surrogates not allowed" in w.sched.procs["a"].reason
    with pytest.raises(StartError):
        await w.sched.wait_ready("b", LIMIT)


async def test_failing_listener_does_not_break_supervision(world_factory: list[World]) -> None:
    """A listener that raises (say, printing to a closed stdout) neither hides a ready
    line nor leaves a transition half done."""
    w = make(world_factory, proc("a", "sh -c 'echo up; exec sleep 60'", ready_regex="^up"),
             proc("b", "sh -c 'exit 3'", restart=model.Restart.ON_FAILURE, restart_limit=1,
                  restart_delay=0.01))

    def broken(*_: object) -> None:
        raise BrokenPipeError("stdout is gone")
    w.sched.output_listeners.insert(0, broken)
    w.sched.transition_listeners.insert(0, broken)
    w.sched.start("all")
    await w.sched.wait_ready("a", LIMIT)
    await until(lambda: "gave up" in w.sched.procs["b"].reason)
    assert w.daemon.spawned.count("b") == 2


async def test_start_replaces_a_pending_restart(world_factory: list[World]) -> None:
    """A start while a restart is pending is that restart: the pending one does not start
    the process once more (after its limit, or out of its back-off)."""
    w = make(world_factory, proc("p", "sh -c 'exit 1'", restart=model.Restart.ON_FAILURE,
                                 restart_limit=1, restart_delay=5.0))
    rt = w.sched.procs["p"]
    w.sched.start("p")
    await w.sched.wait(["p"], {S.FAILED}, LIMIT)  # its restart is due in 5 s
    w.daemon.fail_spawn.add("p")
    w.sched.start("p")
    await until(lambda: "gave up" in rt.reason)
    await until(lambda: not rt.side_tasks)
    assert w.log.count(("p", S.STARTING)) == 2 and rt.state == S.FAILED


async def test_lost_daemon_fails_every_process_it_ran(world_factory: list[World]) -> None:
    """Two node names for one daemon (say `localhost` and the host's name): when its
    connection ends, the processes of both are failed."""
    w = make(world_factory, proc("a", node="localhost"), proc("b", node="thishost"))
    w.sched.start("all")
    await w.sched.wait_ready("all", LIMIT)
    w.daemon.queue.put_nowait(None)  # the connection ended
    await until(lambda: any(rt.state != S.READY for rt in w.sched.procs.values()))
    for name in "ab":  # all at once
        assert w.sched.procs[name].state == S.FAILED
        assert "lost the connection to the ln_daemon" in w.sched.procs[name].reason


async def running_world(world_factory: list[World], daemon: FakeDaemon,
                        *procs: model.Process) -> World:
    """A scheduler that starts everything on `daemon` and is then closed (as a manager that
    died), and a new one for the same daemon that has not attached yet."""
    first = World(config(*procs), daemon)
    world_factory.append(first)
    first.sched.start("all")
    await first.sched.wait_ready("all", LIMIT)
    await first.sched.close()
    second = World(config(*procs), daemon)
    world_factory.append(second)
    return second


async def test_attach_does_not_start_what_runs_already(world_factory: list[World]) -> None:
    """Re-attaching to a ready process with start_on_ready does not start its targets again
    (they run, or were stopped on purpose)."""
    w = await running_world(world_factory, FakeDaemon(), proc("a", start_on_ready=["b"]),
                            proc("b"), proc("c"))
    pids = {n: p.proc.pid for n, p in w.daemon.procs.items()}
    await w.daemon.stop("b")
    await until(lambda: w.daemon.procs["b"].exited is not None)
    await w.sched.attach()
    await until(lambda: all(rt.task is None or rt.task.done() for rt in w.sched.procs.values()))
    assert w.daemon.spawned == ["a", "b", "c"]
    assert {n: rt.state for n, rt in w.sched.procs.items()} == \
        {"a": S.READY, "b": S.FAILED, "c": S.READY}
    assert w.sched.procs["c"].pid == pids["c"]


class ExitDuringAttachDaemon(FakeDaemon):
    """Its process `c` exits while the new scheduler asks for its output (the exit event
    overtakes the answer)."""

    async def output(self, name: str, n: int = 100) -> list[Line]:
        lines = await super().output(name, n)
        p = self.procs[name]
        if name == "c" and p.exited is None:
            os.killpg(p.proc.pid, signal.SIGKILL)
            async with asyncio.timeout(LIMIT):
                while p.exited is None or not self.queue.empty():
                    await asyncio.sleep(0.005)
        return lines


async def test_exit_during_attach_is_seen(world_factory: list[World]) -> None:
    w = await running_world(world_factory, ExitDuringAttachDaemon(), proc("a"), proc("b"),
                            proc("c"))
    await w.sched.attach()
    c = w.sched.procs["c"]
    assert (c.state, c.pid, c.exit_signal) == (S.FAILED, None, signal.SIGKILL)
    assert [w.sched.procs[n].state for n in "ab"] == [S.READY, S.READY]


async def test_reload_removes_a_running_process_once_it_stopped(
        world_factory: list[World]) -> None:
    w = make(world_factory, proc("a"), proc("b"),
             proc("c", "sh -c 'echo up; sleep 0.2; exit 1'", ready_regex="^up",
                  restart=model.Restart.ON_FAILURE, restart_delay=0.01),
             states=(model.State("net", HERE, check="true"),))
    w.sched.start("all")
    await w.sched.wait(["a", "b", "c"], {S.READY}, LIMIT)
    result = w.sched.apply_config(config(proc("a")))
    assert result["removed_when_stopped"] == ["b", "c"]
    assert w.sched.states == {}
    assert w.sched.targets("all") == ["a", "b", "c"]  # still running
    await w.sched.stop("b")
    # c fails: it goes, and is not restarted
    await until(lambda: "c" not in w.sched.procs or w.daemon.spawned.count("c") > 1)
    assert w.sched.targets("all") == ["a"]
    await until(lambda: not w.sched.procs["a"].side_tasks)
    assert w.daemon.spawned == ["a", "b", "c"]


async def test_reload_changes_a_running_process_at_its_next_start(
        world_factory: list[World]) -> None:
    """A running process keeps what it was started with (its node, above all: it is
    stopped through the daemon that runs it) until it starts again."""
    daemons = {"n1": FakeDaemon(), "n2": FakeDaemon()}

    async def link(node: str) -> FakeDaemon:
        return daemons[node]
    w = World(config(proc("a", node="n1", ready_regex="^up",
                          command="sh -c 'echo up; exec sleep 60'")), daemons["n1"])
    w.sched = Scheduler(w.sched.config, w.registry,
                        Backend(link=link, spawn_spec=Spec, exited_type=Exit, output_type=Line,
                                error_type=FakeError), manager_address="127.0.0.1:1")
    world_factory.append(w)
    w.sched.start("a")
    await w.sched.wait_ready("a", LIMIT)
    result = w.sched.apply_config(config(proc("a", node="n2", ready_regex="^never")))
    assert result["changed"] == ["a"]
    stopping = asyncio.create_task(w.sched.stop("a"))
    await until(lambda: stopping.done() or daemons["n2"].stops)
    assert await stopping == ["a"] and daemons["n1"].stops == ["a"]
    assert daemons["n2"].stops == []
    w.sched.start("a")
    await w.sched.wait(["a"], {S.STARTED}, LIMIT)
    assert daemons["n2"].spawned == ["a"]
    await w.sched.stop("a")
    await daemons["n2"].kill_all()


async def test_shutdown_leaves_disable_stop_and_what_it_needs(
        world_factory: list[World]) -> None:
    w = make(world_factory, proc("a"), proc("b", depends_on=["a"], flags={"disable_stop"}),
             proc("c"))
    w.sched.start("all")
    await w.sched.wait_ready("all", LIMIT)
    await w.sched.shutdown()
    assert [w.sched.procs[n].state for n in "abc"] == [S.READY, S.READY, S.STOPPED]
    assert w.daemon.stops == ["c"]


async def test_disable_stop_refusal_stops_nothing(world_factory: list[World]) -> None:
    """Stopping (or restarting) what includes or is needed by a process with disable_stop
    is refused as a whole, before anything is stopped."""
    w = make(world_factory, proc("a"), proc("b", depends_on=["a"], flags={"disable_stop"}),
             proc("c"))
    w.sched.start("all")
    await w.sched.wait_ready("all", LIMIT)
    with pytest.raises(StartError, match="b has the flag disable_stop"):
        await w.sched.restart("all")
    with pytest.raises(StartError, match=r"b has the flag disable_stop \(it depends on a\)"):
        await w.sched.stop("a")
    assert [w.sched.procs[n].state for n in "abc"] == [S.READY] * 3
    await w.sched.restart("c")
    await w.sched.stop("a", force=True)
    assert [w.sched.procs[n].state for n in "ab"] == [S.STOPPED] * 2
    assert sorted(w.daemon.spawned) == ["a", "b", "c", "c"]


class HeldSpawnDaemon(FakeDaemon):
    """Starts the process at once but answers SPAWN only once `answer` is set."""

    def __init__(self) -> None:
        super().__init__()
        self.answer = asyncio.Event()

    async def spawn(self, spec: Spec) -> Info:
        info = await super().spawn(spec)
        await self.answer.wait()
        return info


async def test_stop_while_spawning_waits_for_the_exit(world_factory: list[World],
                                                      tmp_path: Path) -> None:
    """A stop that comes while the daemon is starting the process stops it once it runs,
    and is done (the process `stopped`) only when it has exited: a start right after it
    does not find the old run still there."""
    release = tmp_path / "release"
    w = World(config(proc("p", slow_to_stop(tmp_path, release), ready_regex="^up",
                          term_timeout=LIMIT)), HeldSpawnDaemon())
    world_factory.append(w)
    gone_when_stopped = []
    w.sched.transition_listeners.append(
        lambda n, t: gone_when_stopped.append(w.daemon.procs["p"].exited is not None)
        if t.state == S.STOPPED else None)
    w.sched.start("p")
    await until(lambda: "p" in w.daemon.procs)
    stopping = asyncio.create_task(w.sched.stop("p"))
    await asyncio.sleep(0)
    w.daemon.answer.set()
    await until(lambda: w.daemon.stops == ["p"])
    release.touch()
    assert await stopping == ["p"]
    assert gone_when_stopped == [True]
    w.sched.start("p")
    await w.sched.wait_ready("p", LIMIT)


async def test_close_while_spawning_leaves_the_process(world_factory: list[World]) -> None:
    """Closing the scheduler (detach) while a spawn is on its way stops nothing."""
    w = World(config(proc("p")), HeldSpawnDaemon())
    world_factory.append(w)
    w.sched.start("p")
    await until(lambda: "p" in w.daemon.procs)
    closing = asyncio.create_task(w.sched.close())
    await asyncio.sleep(0)
    w.daemon.answer.set()
    await closing
    assert w.daemon.stops == [] and w.daemon.procs["p"].exited is None


async def test_close_ends_every_task(world_factory: list[World], tmp_path: Path) -> None:
    """After close() no task of the scheduler is left (here: the stop of a dependent whose
    dependency crashed, waiting for an exit)."""
    crash, release = tmp_path / "crash", tmp_path / "release"
    w = make(world_factory, proc("a", crash_once(tmp_path, crash)),
             proc("b", slow_to_stop(tmp_path, release), depends_on=["a"], ready_regex="^up",
                  term_timeout=LIMIT))
    w.sched.start("b")
    await w.sched.wait_ready("all", LIMIT)
    crash.touch()
    await w.sched.wait(["b"], {S.STOPPING}, LIMIT)
    await w.sched.close()
    left = [t for t in asyncio.all_tasks()
            if t.get_coro().__qualname__.startswith(  # type: ignore[union-attr]
                ("Scheduler.", "ManagedProcess.", "StateCommands."))
            and not t.done()]
    assert left == []


async def test_ready_time_does_not_depend_on_the_wall_clock(
        world_factory: list[World], monkeypatch: pytest.MonkeyPatch) -> None:
    """ready_time counts on the monotonic clock: a wall clock set back meanwhile (here: one
    that stands still) does not keep the process from getting ready."""
    from links_and_nodes.manager.processes import managed

    monkeypatch.setattr(managed, "time",
                        SimpleNamespace(time=lambda: 1e9, monotonic=time.monotonic))
    w = make(world_factory, proc("p", ready_time=0.05))
    w.sched.start("p")
    rt = w.sched.procs["p"]
    await w.sched.wait(["p"], {S.STARTED}, LIMIT)
    await until(lambda: not rt.side_tasks)  # the ready timer has run
    assert rt.state == S.READY


async def test_wait_ready_final_waits_through_a_restart(world_factory: list[World],
                                                        tmp_path: Path) -> None:
    """wait_ready(final=True) (--wait-ready) fails only on a failure for good: not on one
    its restart repairs, but at once when a pending restart is called off."""
    gate = tmp_path / "crash"
    gate.touch()
    w = make(world_factory, proc("flaky", crash_once(tmp_path, gate), ready_time=0.05,
                                 restart=model.Restart.ON_FAILURE, restart_delay=0.01),
             proc("slow", "sh -c 'exit 1'", ready_regex="never",
                  restart=model.Restart.ON_FAILURE, restart_delay=LIMIT))
    w.sched.start("flaky")
    await w.sched.wait_ready("flaky", LIMIT, final=True)
    assert w.log.count(("flaky", S.FAILED)) == 1
    await w.sched.stop("flaky")  # nothing else changes from now on
    w.sched.start("slow")
    waiting = asyncio.create_task(w.sched.wait_ready("slow", LIMIT, final=True))
    await w.sched.wait(["slow"], {S.FAILED}, LIMIT)
    assert not waiting.done()  # its restart is pending
    await w.sched.stop("slow")
    with pytest.raises(StartError, match="slow: failed: exit status 1"):
        await waiting


async def test_start_while_stopping_starts_once_stopped(world_factory: list[World],
                                                        tmp_path: Path) -> None:
    """A start asked for while the process is still stopping is not lost: it starts again
    once the stop is done."""
    release = tmp_path / "release"
    w = make(world_factory, proc("p", slow_to_stop(tmp_path, release), ready_regex="^up",
                                 term_timeout=LIMIT))
    rt = w.sched.procs["p"]
    w.sched.start("p")
    await w.sched.wait_ready("p", LIMIT)
    stopping = asyncio.create_task(w.sched.stop("p"))
    await w.sched.wait(["p"], {S.STOPPING}, LIMIT)
    assert w.sched.start("p") == ["p"]
    release.touch()
    await stopping
    assert rt.state in (S.STARTING, S.STARTED, S.READY)
    await w.sched.wait_ready("p", LIMIT)
    assert w.daemon.spawned == ["p", "p"]


async def test_one_failed_dependency_fails_the_start_at_once(
        world_factory: list[World]) -> None:
    """A dependency that fails ends the start even while another one is still on its way
    (here: never ready)."""
    w = make(world_factory, proc("a"), proc("b", ready_regex="never"),
             proc("c", depends_on=["a", "b"]))
    w.daemon.fail_spawn.add("a")
    w.sched.start("c")
    with pytest.raises(StartError, match="command not found"):
        await w.sched.wait_ready("a", LIMIT)
    await w.sched.wait(["b"], {S.STARTED}, LIMIT)
    c = w.sched.procs["c"]
    assert c.task is not None
    await asyncio.wait([c.task], timeout=LIMIT)
    assert c.state == S.FAILED and "dependency a did not become ready" in c.reason
    assert w.sched.procs["b"].state == S.STARTED  # it goes on starting by itself


async def test_wait_with_zero_timeout_sees_what_holds_now(world_factory: list[World]) -> None:
    w = make(world_factory, proc("a"))
    w.sched.start("a")
    await w.sched.wait_ready("a", LIMIT)
    await w.sched.wait_ready("a", 0)


async def test_back_off_after_many_restarts(world_factory: list[World]) -> None:
    """The delay stays at its cap however many restarts came before (2 ** 1100 is too large
    for a float)."""
    w = make(world_factory, proc("p", "sh -c 'exit 1'", restart=model.Restart.ON_FAILURE,
                                 restart_limit=10**6, restart_delay=0.01))
    rt = w.sched.procs["p"]
    rt.restarts = 1100  # a long-running system
    w.sched.start("p")
    await w.sched.wait(["p"], {S.FAILED}, LIMIT)
    assert rt.restarts == 1101
    assert rt.restart_task is not None and not rt.restart_task.done()


async def test_dependent_started_while_its_dependency_stops_is_stopped_too(
        world_factory: list[World], tmp_path: Path) -> None:
    """`start c` while `stop a` waits for a's other dependents: c, started on a that was
    still ready, does not keep running on a stopped dependency."""
    release = tmp_path / "release"
    w = make(world_factory, proc("a"),
             proc("b", slow_to_stop(tmp_path, release), depends_on=["a"], ready_regex="^up",
                  term_timeout=LIMIT),
             proc("c", depends_on=["a"]))
    w.sched.start("b")
    await w.sched.wait_ready("b", LIMIT)
    stopping = asyncio.create_task(w.sched.stop("a"))
    await w.sched.wait(["b"], {S.STOPPING}, LIMIT)
    w.sched.start("c")
    await w.sched.wait(["c"], {S.READY, S.FAILED}, LIMIT)
    release.touch()
    await stopping
    assert {n: w.sched.procs[n].state for n in "abc"} == \
        {"a": S.STOPPED, "b": S.STOPPED, "c": S.STOPPED}
