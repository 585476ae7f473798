"""One managed process, in Supervisor's shape: its state (over states.py), the action
pending for it, and its own behaviour: spawning it, its readiness, its exit, its restart
policy and its watchdog.  The scheduler (scheduler.py) keeps the dependency graph and the
daemon connections; a process reaches them through its `Owner`."""

from __future__ import annotations

import asyncio
import contextlib
import enum
import logging
import re
import signal
import time
from collections import deque
from collections.abc import Awaitable
from dataclasses import dataclass
from typing import Any, Protocol

from ..config import model
from .backend import Backend, DaemonLink, Registry, StartError
from .changes import Changes
from .daemon_resources import ProcessSample
from .daemon_wire import Exited, OutputLine, ProcessInfo, SpawnSpec
from .resources import limit_problem
from .states import ALIVE, STARTABLE, ProcState, check_transition

log = logging.getLogger("ln_manager")

S = ProcState
MAX_RESTART_DELAY = 30.0  # seconds
STABLE_AFTER = 10.0  # seconds ready after which a process's restart count starts again


class Pending(enum.Enum):
    """What is asked of a process beyond its state; it decides what its next exit (or the
    end of its stop) means.  `ManagedProcess.why` holds the detail named below."""

    NONE = "none"  # nothing: an exit follows the restart policy
    STOP = "stop"  # a stop: it stays down
    START = "start"  # a start while it was stopping: it starts once stopped
    RETURN = "return"  # stopped with dependency `why`: starts again once that is ready
    WATCHDOG = "watchdog"  # its watchdog (`why`) stops it: the exit is a failure, restarted


# Pending actions under which the process is being (or has been) stopped on request.
STOP_ASKED = frozenset({Pending.STOP, Pending.START, Pending.RETURN})


@dataclass
class Transition:
    time: float  # time.time()
    state: ProcState
    reason: str


class Owner(Protocol):
    """What a process uses of its scheduler."""

    registry: Registry
    backend: Backend
    changed: Changes

    async def link(self, node: str) -> DaemonLink: ...
    async def admit(self, node: str) -> None: ...
    def spawn_request(self, cfg: model.Process) -> SpawnSpec: ...
    async def dependencies(self, proc: ManagedProcess) -> None: ...
    def is_current(self, proc: ManagedProcess) -> bool: ...
    def transitioned(self, proc: ManagedProcess, t: Transition) -> None: ...
    def went_down(self, proc: ManagedProcess) -> None: ...
    def became_ready(self, proc: ManagedProcess, attached: bool) -> None: ...
    def may_return_with(self, dependency: str) -> bool: ...


class Readiness:
    """Which of a run's readiness conditions that the process itself shows have held."""

    def __init__(self, cfg: model.Process) -> None:
        self.regex = re.compile(cfg.ready_regex) if cfg.ready_regex is not None else None
        self.regex_seen = False
        self.time_passed = False  # its ready_time (monotonic) has passed

    def reset(self) -> None:
        self.regex_seen = self.time_passed = False

    def saw(self, text: str) -> bool:
        """Whether this output line is the first to match ready_regex."""
        if self.regex is None or self.regex_seen or not self.regex.search(text):
            return False
        self.regex_seen = True
        return True


class ManagedProcess:
    """What the scheduler knows of one configured process, and what it does by itself."""

    def __init__(self, cfg: model.Process, owner: Owner) -> None:
        self.cfg = cfg
        self.owner = owner
        self.state = S.STOPPED
        self.pid: int | None = None
        self.reason = ""  # why it is in its state (failure text, "stopped by request", ...)
        self.exit_code: int | None = None
        self.exit_signal: int | None = None
        self.started_at: float | None = None  # time.time()
        self.ready_at: float | None = None  # time.monotonic(), for the restart count
        self.ready_wall: float | None = None  # time.time()
        self.restarts = 0  # restarts in a row
        self.output: deque[OutputLine] = deque(maxlen=max(1, cfg.max_output_lines))
        self.transitions: list[Transition] = []
        self.pending = Pending.NONE
        self.why = ""  # the pending action's detail (see Pending)
        self.next_cfg: model.Process | None = None  # from a reload while it ran
        self.removed = False  # no longer configured: goes as soon as it is not running
        self.daemon_record = False  # the daemon may still hold a record of an earlier run
        self.link: DaemonLink | None = None  # the daemon connection of its run
        self.early_exit: Exited | None = None  # an exit that came before the spawn answer
        self.readiness = Readiness(cfg)
        self.task: asyncio.Task[None] | None = None  # starting (dependencies, spawn, readiness)
        self.side_tasks: set[asyncio.Task[Any]] = set()  # watchdog, ready and restart timers
        self.restart_task: asyncio.Task[None] | None = None  # the last restart timer
        self.limit = ""  # why its run is over its max_rss/max_cpu, "" while it is not
        self._limits_hit: frozenset[str] = frozenset()  # which of them

    def as_dict(self) -> dict[str, Any]:
        return {"name": self.cfg.name, "state": self.state.value, "pid": self.pid,
                "node": self.cfg.node, "reason": self.reason, "exit_code": self.exit_code,
                "exit_signal": self.exit_signal, "restarts": self.restarts,
                "started_at": self.started_at, "ready_at": self.ready_wall,
                "limit": self.limit}

    @property
    def stop_asked(self) -> bool:
        return self.pending in STOP_ASKED

    @property
    def returns_with(self) -> str | None:
        """The dependency whose loss stopped it, with which it comes back."""
        return self.why if self.pending is Pending.RETURN else None

    # ---- transitions ---------------------------------------------------------------------
    def transition(self, state: ProcState, reason: str = "") -> None:
        check_transition(self.state, state)
        self.state = state
        self.reason = reason
        t = Transition(time.time(), state, reason)
        self.transitions.append(t)
        if state == S.READY:
            self.ready_at = time.monotonic()
            self.ready_wall = t.time
        log.info("process %s: %s%s", self.cfg.name, state.value,
                 f" ({reason})" if reason else "")
        self.owner.transitioned(self, t)

    def _note(self, reason: str) -> None:
        """A new reason for the state it stays in."""
        self.reason = reason
        t = Transition(time.time(), self.state, reason)
        self.transitions.append(t)
        log.warning("process %s: %s", self.cfg.name, reason)
        self.owner.transitioned(self, t)

    # ---- pending actions -----------------------------------------------------------------
    def ask_start(self) -> asyncio.Task[None] | None:
        """A start on request: one asked while it is stopping follows the stop."""
        if self.pending is Pending.RETURN:
            self.pending = Pending.STOP  # started by request, not with its dependency
        if self.state == S.STOPPING and self.pending in STOP_ASKED:
            self.pending = Pending.START
        return self.launch()

    def ask_stop(self, returns_with: str | None = None) -> None:
        """A stop: for good, or (`returns_with`) until that dependency is ready again."""
        if returns_with is None:
            self.pending, self.why = Pending.STOP, ""
        elif self.pending is not Pending.START:
            self.pending, self.why = Pending.RETURN, returns_with

    def configure(self) -> None:
        """Take the settings of the last reload (before it starts)."""
        cfg, self.next_cfg = self.next_cfg, None
        if cfg is None:
            return
        self.cfg = cfg
        self.readiness.regex = (re.compile(cfg.ready_regex) if cfg.ready_regex is not None
                                else None)
        if self.output.maxlen != max(1, cfg.max_output_lines):
            self.output = deque(self.output, maxlen=max(1, cfg.max_output_lines))

    def restore(self) -> None:
        """Once stopped: a start asked for while it was stopping happens now, and a process
        stopped with a dependency comes back if that is ready again."""
        if self.state not in STARTABLE:
            return
        if self.pending is Pending.START or (
                self.pending is Pending.RETURN and self.owner.may_return_with(self.why)):
            self.launch()

    # ---- starting ------------------------------------------------------------------------
    def launch(self) -> asyncio.Task[None] | None:
        """Start its start task unless it runs or is up already."""
        if self.task is not None and not self.task.done():
            return self.task
        if self.state not in STARTABLE or not self.owner.is_current(self):
            return None  # running, or removed by a reload
        self.configure()
        self.cancel_side()  # a pending restart: this start is it
        self.pending, self.why = Pending.NONE, ""
        self.ready_at = None  # the restart count looks at how long this run stays ready
        self.transition(S.STARTING)
        self.task = asyncio.get_running_loop().create_task(self._start())
        return self.task

    async def _start(self) -> None:
        try:
            await self.owner.dependencies(self)
            await self._spawn()
        except asyncio.CancelledError:
            if self.state == S.STARTING:
                self.transition(S.STOPPED, "start cancelled")
            raise
        except StartError as exc:
            if self.state == S.STARTING:
                self.transition(S.FAILED, str(exc))
                self._after_failure()
        except Exception as exc:  # a bug, or a request the daemon client cannot encode
            log.exception("process %s: cannot start", self.cfg.name)
            if self.state == S.STARTING:
                self.transition(S.FAILED, f"cannot start: {exc}")
                self._after_failure()

    async def _spawn(self) -> None:
        cfg, backend = self.cfg, self.owner.backend
        await self.owner.admit(cfg.node)
        try:
            link = await self.owner.link(cfg.node)
        except (OSError, backend.error_type) as exc:
            raise StartError(f"cannot start: {exc}") from None
        spec = self.owner.spawn_request(cfg)
        # A record of an earlier run of this name would answer SPAWN with "exists".
        if self.daemon_record:
            with contextlib.suppress(backend.error_type):
                await link.forget(cfg.name)
            self.daemon_record = False
        # Reset before the spawn, not after: the new run's first output can be handled
        # before this task resumes with the daemon's answer.
        self.readiness.reset()
        self.early_exit = None
        spawning = asyncio.ensure_future(link.spawn(spec))
        try:
            info = await asyncio.shield(spawning)
        except backend.error_type as exc:
            raise StartError(f"cannot start: {exc}") from None
        except asyncio.CancelledError:
            # Stopped while the daemon was starting it: let that finish, then stop it and
            # wait for its exit, so nothing runs that the scheduler believes stopped.  (Without
            # a stop request this is the scheduler closing: the process runs on.)
            if self.stop_asked:
                with contextlib.suppress(Exception):
                    await self._stop_spawned(link, await spawning)
            raise
        self.pid = info.pid
        self.link = link
        self.daemon_record = True
        self.started_at = time.time()
        self.exit_code = self.exit_signal = None
        early, self.early_exit = self.early_exit, None
        if self.state != S.STARTING:  # stopped (or exited) while the spawn was on its way
            return
        if early is not None and early.pid == info.pid:  # it has already exited
            self.on_exit(early.exit_code, early.signal)
            return
        if not cfg.has_readiness:
            self.transition(S.READY, "started (no readiness condition)")
            self._on_ready()
            return
        self.transition(S.STARTED, f"pid {info.pid}")
        if cfg.ready_time is not None:
            self.side(self._ready_timer(cfg.ready_time))
        self.check_ready()

    async def _stop_spawned(self, link: DaemonLink, info: ProcessInfo) -> None:
        """Stop the run the daemon started while this process was being stopped (still
        `starting`); return once it has exited."""
        self.pid, self.link, self.daemon_record = info.pid, link, True
        early, self.early_exit = self.early_exit, None
        if early is not None and early.pid == info.pid:
            self.pid = None  # it has exited already
            return
        with contextlib.suppress(self.owner.backend.error_type):  # it may have exited
            await link.stop(self.cfg.name)
        # its exit (on_exit) or the connection's loss clears it
        await self.owner.changed.wait_for(lambda: self.pid != info.pid)

    # ---- readiness -----------------------------------------------------------------------
    async def _ready_timer(self, delay: float) -> None:
        await asyncio.sleep(delay)
        self.readiness.time_passed = True
        self.check_ready()

    def saw_line(self, line: OutputLine) -> None:
        if self.readiness.saw(line.text):
            self.check_ready()

    def check_ready(self, *, attached: bool = False) -> None:
        """READY once every readiness condition holds (`attached`: found so by a new
        manager)."""
        if self.state != S.STARTED:
            return
        cfg, registry = self.cfg, self.owner.registry
        held = []
        if cfg.ready_regex is not None:
            if not self.readiness.regex_seen:
                return
            held.append(f"output matched {cfg.ready_regex!r}")
        if cfg.ready_time is not None:
            if not self.readiness.time_passed:
                return
            held.append(f"{cfg.ready_time:g} s passed")
        if cfg.ready_on_topic is not None:
            if registry.topic_publishers(cfg.ready_on_topic) == 0:
                return
            held.append(f"topic {cfg.ready_on_topic} has a publisher")
        if cfg.ready_on_service is not None:
            if not registry.service_provided(cfg.ready_on_service):
                return
            held.append(f"service {cfg.ready_on_service} is registered")
        self.transition(S.READY, ", ".join(held))
        self._on_ready(attached=attached)

    def _on_ready(self, *, attached: bool = False) -> None:
        """Its watchdog; then the scheduler starts what waits for it."""
        if self.cfg.watchdog is not None:
            self.side(self._watchdog(self.cfg.watchdog))
        self.owner.became_ready(self, attached)

    # ---- found running by a new manager --------------------------------------------------
    def adopt(self, link: DaemonLink, info: ProcessInfo, recent: list[OutputLine]) -> None:
        """Its state as the daemon has it: `started` (see resume), or exited (before or
        while this scheduler attached)."""
        self.link = link
        newer = [line for line in self.output if not recent or line.time > recent[-1].time]
        self.output.clear()
        self.output.extend(recent)
        self.output.extend(newer)  # came as events while attaching
        self.started_at = info.started
        running = info.state in ("running", "stopping")
        if running and self.pid == info.pid:
            regex = self.readiness.regex
            if regex is not None:
                self.readiness.regex_seen = self.readiness.regex_seen or any(
                    regex.search(line.text) for line in recent)
            self.transition(S.STARTED, f"re-attached to pid {info.pid}")
            return
        if not running:
            self.exit_code, self.exit_signal = info.exit_code, info.signal
        # else it exited while attaching: on_exit kept its status
        ok = self.exit_code == 0 and self.exit_signal is None
        self.transition(S.FINISHED if ok else S.FAILED,
                        f"exited while no manager was attached (exit status "
                        f"{self.exit_code}, signal {self.exit_signal})")

    def resume(self, info: ProcessInfo) -> None:
        """Its readiness, adopted `started`: as far as its run has got."""
        if self.state != S.STARTED:
            return
        if not self.cfg.has_readiness:
            self.transition(S.READY, "re-attached (no readiness condition)")
            self._on_ready(attached=True)
            return
        if self.cfg.ready_time is not None:
            left = self.cfg.ready_time - (time.time() - info.started)
            if left > 0:
                self.side(self._ready_timer(left))
            else:
                self.readiness.time_passed = True
        self.check_ready(attached=True)

    # ---- stopping and exits --------------------------------------------------------------
    async def stop(self, reason: str) -> None:
        """Bring it down (its dependents are down already); return once it is."""
        self.cancel_side()
        if self.task is not None and not self.task.done() \
                and self.task is not asyncio.current_task():
            self.task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self.task
        if self.state == S.STARTING:
            self.transition(S.STOPPED, reason)
        if self.state in STARTABLE:
            self.restore()
        if self.state in (S.STARTED, S.READY):
            self.transition(S.STOPPING, reason)
            await self._daemon_stop()
        if self.state == S.STOPPING:
            # not "until stopped": a restored dependent may be starting again at once
            await self.owner.changed.wait_for(lambda: self.state != S.STOPPING)

    async def _daemon_stop(self) -> None:
        try:
            await (await self.owner.link(self.cfg.node)).stop(self.cfg.name)
        except (OSError, self.owner.backend.error_type) as exc:
            log.warning("process %s: stop failed: %s", self.cfg.name, exc)

    def exited(self, event: Exited) -> None:
        if self.pid == event.pid:
            self.on_exit(event.exit_code, event.signal)
        elif self.state == S.STARTING:
            self.early_exit = event  # the spawn answer is still on its way

    def on_exit(self, code: int | None, sig: int | None) -> None:
        self.exit_code, self.exit_signal = code, sig
        self.pid = None
        self.limit, self._limits_hit = "", frozenset()
        self.cancel_side()
        if self.state not in ALIVE and self.state != S.STARTING:
            return
        how = (f"exit status {code}" if sig is None
               else f"killed by {signal.Signals(sig).name if sig in _SIGNALS else sig}")
        if self.stop_asked:
            self.transition(S.STOPPED, f"{self.reason or 'stopped'}; {how}")
            self.restore()
            return
        if self.pending is Pending.WATCHDOG:
            why, self.pending, self.why = self.why, Pending.NONE, ""
            self.transition(S.FAILED, f"{why}; {how}")
            self.owner.went_down(self)
            self._schedule_restart()
            return
        if self.state == S.STARTING:  # exited before the spawn answer was processed
            self.transition(S.STARTED, "")
        failed = not ((code == 0 and sig is None) or "no_error_on_stop" in self.cfg.flags)
        self.transition(S.FAILED if failed else S.FINISHED, how)
        self.owner.went_down(self)
        restart = self.cfg.restart
        if restart == model.Restart.ALWAYS or (restart == model.Restart.ON_FAILURE and failed):
            self._schedule_restart()

    def daemon_lost(self, link: DaemonLink) -> None:
        """The daemon connection `link` ended: its run through it is unknown now, and fails
        (restarted by its policy, through a new connection)."""
        if self.link is link and self.pid is not None and self.state == S.STARTING:
            self.pid = None  # being stopped while it was spawned (_stop_spawned)
            self.owner.changed.notify()
        if self.state not in ALIVE or self.link is not link:
            return
        self.pid = None
        self.cancel_side()
        if self.stop_asked:
            self.transition(S.STOPPED, "stopped (daemon connection lost)")
            self.restore()
            return
        self.transition(S.FAILED, f"lost the connection to the ln_daemon of node "
                                  f"{self.cfg.node!r}")
        self.owner.went_down(self)
        if self.cfg.restart != model.Restart.NEVER:
            self._schedule_restart()

    # ---- restart policy and watchdog -----------------------------------------------------
    def _after_failure(self) -> None:
        if self.cfg.restart != model.Restart.NEVER and not self.stop_asked:
            self._schedule_restart()

    def _schedule_restart(self) -> None:
        if self.ready_at is not None and time.monotonic() - self.ready_at >= STABLE_AFTER:
            self.restarts = 0
        if self.restarts >= self.cfg.restart_limit:
            self._note(f"gave up after {self.restarts} restarts; last: {self.reason}")
            return
        # (2 ** restarts no longer fits a float after 1023 restarts)
        delay = min(MAX_RESTART_DELAY,
                    self.cfg.restart_delay * 2.0 ** min(self.restarts, 1000))
        self.restarts += 1
        log.info("process %s: restart %d of %d in %.3g s", self.cfg.name, self.restarts,
                 self.cfg.restart_limit, delay)
        self.restart_task = self.side(self._restart_later(delay))
        # (also when cancelled: a wait for its final state looks again)
        self.restart_task.add_done_callback(lambda _: self.owner.changed.notify())

    async def _restart_later(self, delay: float) -> None:
        await asyncio.sleep(delay)
        if self.state in STARTABLE and not self.stop_asked:
            self.launch()

    async def _watchdog(self, wd: model.Watchdog) -> None:
        registry = self.owner.registry
        window = max(1.0, 3.0 / wd.min_hz)
        before = await registry.topic_published(wd.topic)
        while self.state == S.READY:
            await asyncio.sleep(window)
            now = await registry.topic_published(wd.topic)
            rate = (now - before) / window
            before = now
            if rate < wd.min_hz and self.state == S.READY:
                why = f"watchdog: {wd.topic} at {rate:.3g} Hz < {wd.min_hz:g} Hz"
                log.warning("process %s: %s: restarting", self.cfg.name, why)
                self.pending, self.why = Pending.WATCHDOG, why
                self.transition(S.STOPPING, why)
                await self._daemon_stop()
                return  # its exit is a failure that restarts it (on_exit)

    def resources(self, sample: ProcessSample) -> None:
        """A resource sample of its current run: over `max_rss`/`max_cpu` it is flagged with a
        warning (once per limit it goes over), and with `on_limit: restart` restarted as a
        failure; the flag goes when a sample is within its limits again."""
        problem = limit_problem(self.cfg, sample)
        hit = frozenset(k for k in ("max_rss", "max_cpu") if k in problem)
        changed = problem != self.limit
        new = hit - self._limits_hit
        self.limit, self._limits_hit = problem, hit
        if new:
            log.warning("process %s: over its limit: %s", self.cfg.name, problem)
            if self.cfg.on_limit is model.OnLimit.RESTART and self.state in (S.STARTED, S.READY) \
                    and self.pending is Pending.NONE:
                why = f"over its limit: {problem}"
                self.pending, self.why = Pending.WATCHDOG, why  # its exit is a failure
                self.transition(S.STOPPING, why)
                self.side(self._daemon_stop())
        elif changed and not hit and not problem:
            log.info("process %s: within its limits again", self.cfg.name)
        if changed:
            self.owner.changed.notify()

    # ---- side tasks ----------------------------------------------------------------------
    def side(self, coro: Awaitable[None]) -> asyncio.Task[None]:
        task = asyncio.get_running_loop().create_task(coro)  # type: ignore[arg-type]
        self.side_tasks.add(task)
        task.add_done_callback(self.side_tasks.discard)
        return task

    def cancel_side(self) -> None:
        current = asyncio.current_task()
        for task in list(self.side_tasks):
            if task is not current:
                task.cancel()


_SIGNALS = {int(s) for s in signal.Signals}
