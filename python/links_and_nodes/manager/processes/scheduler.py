"""The scheduler: brings the processes of a loaded configuration up in dependency order,
gated on real readiness, keeps them supervised (restart policies, rate watchdogs) and takes
them down dependents first.  It drives one ln_daemon per host through `DaemonLink`s and
asks the manager's registry (core.Core) whether topics have publishers and services are
registered.  States and transitions: process_states.py; the rules: docs/process_management.md.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import logging
import os
import re
import signal
import time
from collections import deque
from collections.abc import Awaitable, Callable, Iterable
from dataclasses import dataclass, field
from typing import Any, Protocol

from ..config import model
from .changes import Changes
from .daemon_wire import Exited, OutputLine, ProcessInfo, SpawnSpec, StateChanged
from .states import ALIVE, STARTABLE, ProcState, check_transition

log = logging.getLogger("ln_manager")

S = ProcState
MAX_RESTART_DELAY = 30.0  # seconds
STABLE_AFTER = 10.0  # seconds ready after which a process's restart count starts again
BASE_ENV = ("PATH", "HOME", "USER", "LOGNAME", "LANG", "LC_ALL", "TZ", "TERM")
X11_ENV = ("DISPLAY", "XAUTHORITY")  # passed with the flag forward_x11


# ---- what the scheduler needs of a daemon connection (daemon_client.DaemonClient) ---------
# The daemon's events as its client queues them; None, last, when the connection is gone.
DaemonEvent = OutputLine | Exited | StateChanged


class DaemonLink(Protocol):
    async def spawn(self, spec: SpawnSpec) -> ProcessInfo: ...
    async def stop(self, name: str) -> None: ...
    async def list(self) -> list[ProcessInfo]: ...
    async def output(self, name: str, n: int = 100) -> list[OutputLine]: ...
    async def forget(self, name: str) -> None: ...
    def events(self) -> asyncio.Queue[DaemonEvent | None]: ...


class Registry(Protocol):
    """What readiness and watchdogs ask the manager (core.Core implements it)."""

    listeners: list[Callable[[], None]]

    def topic_publishers(self, name: str) -> int: ...
    async def topic_published(self, name: str) -> int: ...
    def service_provided(self, name: str) -> bool: ...


@dataclass
class Backend:
    """How the scheduler reaches daemons: `link(node)` returns the (connected) daemon of a
    node; `error_type` is what its calls raise when the daemon refuses.  Requests and events
    are the daemon wire's records (daemon_wire.SpawnSpec, Exited, OutputLine ...);
    `spawn_spec`, `exited_type` and `output_type` name them (a test may narrow them)."""

    link: Callable[[str], Awaitable[DaemonLink]]
    error_type: type[Exception]
    spawn_spec: Callable[..., SpawnSpec] = SpawnSpec
    exited_type: type[Exited] = Exited
    output_type: type[OutputLine] = OutputLine


def spawn_fields(cfg: model.Process, env: list[str]) -> dict[str, Any]:
    """The SpawnSpec of a configured process, as keywords.  The fields whose shape differs
    between the configuration and the wire are converted here; every other field of
    SpawnSpec (a SPAWN field of wire/daemon.schema) is taken from the process's attribute of
    the same name, so a key the daemon applies needs no line here."""
    shaped: dict[str, Any] = dict(
        name=cfg.name, command=cfg.command, shell="start_in_shell" in cfg.flags,
        argv=cfg.argv or None, env=env, cwd=cfg.change_directory,
        rlimits=[(r.name, r.soft, r.hard) for r in cfg.resource_limits],
        policy=cfg.policy.value, use_pty="no_pty" not in cfg.flags,
        output_log=((cfg.output_log.path, cfg.output_log.size_limit,
                     cfg.output_log.keep_count) if cfg.output_log else None))
    for f in dataclasses.fields(SpawnSpec):
        if f.name not in shaped and hasattr(cfg, f.name):
            shaped[f.name] = getattr(cfg, f.name)
    return shaped


@dataclass
class Transition:
    time: float  # time.time()
    state: ProcState
    reason: str


@dataclass
class Runtime:
    """What the scheduler knows of one configured process."""

    cfg: model.Process
    state: ProcState = S.STOPPED
    pid: int | None = None
    reason: str = ""  # why it is in its state (failure text, "stopped by request", ...)
    exit_code: int | None = None
    exit_signal: int | None = None
    started_at: float | None = None  # time.time()
    ready_at: float | None = None  # time.monotonic(), for the restart count
    ready_wall: float | None = None  # time.time()
    restarts: int = 0  # restarts in a row
    output: deque[OutputLine] = field(default_factory=deque)
    transitions: list[Transition] = field(default_factory=list)
    stop_requested: bool = False
    start_requested: bool = False  # asked to start while stopping: starts once stopped
    stopped_for: str | None = None  # dependency whose loss stopped it (restarted with it)
    next_cfg: model.Process | None = None  # from a reload while it ran: for its next start
    removed: bool = False  # no longer configured: goes as soon as it is not running
    watchdog_fired: str | None = None  # why the watchdog is stopping it (then restarts it)
    daemon_record: bool = False  # the daemon may still hold a record of an earlier run
    link: DaemonLink | None = None  # the daemon connection it was started (or found) through
    early_exit: Exited | None = None  # an exit event that came before the daemon's spawn answer
    regex: re.Pattern[str] | None = None
    regex_seen: bool = False
    ready_time_passed: bool = False  # its ready_time (monotonic) has passed
    task: asyncio.Task[None] | None = None  # starting (dependencies, spawn, readiness)
    side_tasks: set[asyncio.Task[Any]] = field(default_factory=set)  # watchdog, restart timer
    restart_task: asyncio.Task[None] | None = None  # the last restart timer (a side task)

    def as_dict(self) -> dict[str, Any]:
        return {"name": self.cfg.name, "state": self.state.value, "pid": self.pid,
                "node": self.cfg.node, "reason": self.reason, "exit_code": self.exit_code,
                "exit_signal": self.exit_signal, "restarts": self.restarts,
                "started_at": self.started_at, "ready_at": self.ready_wall}


@dataclass
class StateRuntime:
    cfg: model.State
    up: bool | None = None
    checked_at: float = 0.0
    lock: asyncio.Lock = field(default_factory=asyncio.Lock)


class StartError(Exception):
    """A process (or state) could not be brought up; the text says why."""


class RateLimiter:
    """At most `rate` starts per second on one host (None: no limit)."""

    def __init__(self, rate: float | None) -> None:
        self.interval = 1.0 / rate if rate else 0.0
        self._next = 0.0
        self._lock = asyncio.Lock()

    async def acquire(self) -> None:
        if not self.interval:
            return
        async with self._lock:
            now = time.monotonic()
            if self._next > now:
                await asyncio.sleep(self._next - now)
            self._next = max(now, self._next) + self.interval


class Scheduler:
    def __init__(self, config: model.Config, registry: Registry, backend: Backend, *,
                 manager_address: str, extra_env: dict[str, str] | None = None,
                 manager_address_for: Callable[[str], str] | None = None) -> None:
        self.config = config
        self.registry = registry
        self.backend = backend
        self.manager_address = manager_address
        # The manager's address as processes on a node reach it (app.py gives one for
        # configurations spanning several hosts); by default the same for every node.
        self.manager_address_for: Callable[[str], str] = \
            manager_address_for or (lambda node: manager_address)
        self.extra_env = dict(extra_env or {})
        self.procs: dict[str, Runtime] = {}
        for name, cfg in config.processes.items():
            rt = Runtime(cfg, output=deque(maxlen=max(1, cfg.max_output_lines)))
            if cfg.ready_regex is not None:
                rt.regex = re.compile(cfg.ready_regex)
            self.procs[name] = rt
        self.states = {name: StateRuntime(cfg) for name, cfg in config.states.items()}
        self._changed = Changes()
        self._limiters: dict[str, RateLimiter] = {}
        self._event_tasks: dict[int, asyncio.Task[None]] = {}
        self._links: dict[str, DaemonLink] = {}
        self._transient = 0
        # transient runs (state commands): their exit, and the daemon connection they use
        self._waiters: dict[str, tuple[asyncio.Future[Exited], DaemonLink]] = {}
        self._bg: set[asyncio.Task[Any]] = set()  # stops of dependents
        self.output_listeners: list[Callable[[str, OutputLine], None]] = []
        self.transition_listeners: list[Callable[[str, Transition], None]] = []
        registry.listeners.append(self._registry_changed)

    # ---- public API ----------------------------------------------------------------------
    def targets(self, target: str) -> list[str]:
        """Process names of a process, a group (recursively) or "all"; KeyError if none."""
        if target == "all":
            return list(self.procs)
        if target in self.procs:
            return [target]
        if target in self.config.groups:
            out: list[str] = []
            self._group_members(target, out, set())
            return out
        raise KeyError(f"no process or group named {target!r}")

    def start(self, target: str) -> list[str]:
        """Start what `target` names (and its dependencies); returns at once."""
        names = self.targets(target)
        for name in names:
            rt = self.procs[name]
            rt.stopped_for = None
            if rt.state == S.STOPPING:
                rt.start_requested = True  # _restore starts it once it stopped
            self._launch(rt)
        return names

    async def stop(self, target: str, *, force: bool = False) -> list[str]:
        """Stop what `target` names, dependents first; returns when all are down.
        StartError, and nothing is stopped, if that includes a process with the flag
        disable_stop (unless `force`)."""
        names = self.targets(target)
        if not force:
            self._refuse_disable_stop(names)
        await asyncio.gather(*(self._stop(self.procs[n], "stopped by request", force=force)
                               for n in names))
        return names

    def _refuse_disable_stop(self, names: list[str]) -> None:
        """StartError if stopping `names` would stop a process with disable_stop: one of
        them, or a running dependent (which is stopped first)."""
        todo = [(name, "") for name in names]
        seen: set[str] = set()
        while todo:
            name, why = todo.pop()
            if name in seen:
                continue
            seen.add(name)
            if "disable_stop" in self.procs[name].cfg.flags:
                raise StartError(f"{name} has the flag disable_stop{why}")
            todo += [(d.cfg.name, f" (it depends on {name})")
                     for d in self._dependents(name) if d.state not in STARTABLE]

    async def restart(self, target: str) -> list[str]:
        names = await self.stop(target)
        for name in names:
            rt = self.procs.get(name)
            if rt is not None:  # not removed by a reload meanwhile
                rt.restarts = 0
                self._launch(rt)
        return names

    async def wait(self, names: Iterable[str], states: set[ProcState],
                   timeout: float | None = None, *, fail_on: set[ProcState] | None = None,
                   final: bool = False) -> None:
        """Until every process of `names` is in one of `states`; StartError if one reaches
        `fail_on` first (its reason; with `final` only if no restart of it is pending),
        TimeoutError after `timeout` seconds."""
        rts = [self.procs[n] for n in names]
        fail_on = fail_on or set()

        def done() -> bool:
            for rt in rts:
                if rt.state in fail_on and rt.state not in states and not (
                        final and rt.restart_task is not None and not rt.restart_task.done()):
                    raise StartError(f"{rt.cfg.name}: {rt.state.value}: {rt.reason}")
            return all(rt.state in states for rt in rts)

        if not done():  # (a timeout of 0 only looks)
            await asyncio.wait_for(self._changed.wait_for(done), timeout)

    async def wait_ready(self, target: str = "all", timeout: float | None = None, *,
                         final: bool = False) -> None:
        """Until every process of `target` is ready (or finished, for ones that ran to
        completion); StartError as soon as one fails (`final`: fails for good, with no
        restart pending)."""
        await self.wait(self.targets(target), {S.READY, S.FINISHED}, timeout,
                        fail_on={S.FAILED}, final=final)

    def status(self) -> list[dict[str, Any]]:
        return [rt.as_dict() for rt in self.procs.values()]

    def history(self, name: str) -> list[Transition]:
        return list(self.procs[name].transitions)

    def output(self, name: str, n: int = 100) -> list[OutputLine]:
        lines = list(self.procs[name].output)
        return lines[-n:] if n > 0 else []

    async def attach(self) -> None:
        """Take over processes a daemon still runs for this instance (a new manager after
        the old one died): their true states and recent output."""
        found: list[tuple[Runtime, DaemonLink, ProcessInfo]] = []
        nodes = {rt.cfg.node for rt in self.procs.values()}
        for node in sorted(nodes):
            try:
                link = await self._link(node)
                infos = await link.list()
            except (OSError, self.backend.error_type) as exc:
                log.warning("cannot ask the daemon of node %r for its processes: %s", node, exc)
                continue
            for info in infos:
                rt = self.procs.get(info.name)
                if rt is None or rt.cfg.node != node or rt.state != S.STOPPED:
                    continue
                rt.daemon_record = True
                if info.state in ("running", "stopping"):
                    rt.pid = info.pid  # an exit from now on clears it (_on_exit)
                found.append((rt, link, info))
        adopted = []
        for rt, link, info in found:
            try:
                recent = await link.output(info.name, rt.cfg.max_output_lines)
            except (OSError, self.backend.error_type) as exc:
                log.warning("process %s: cannot re-attach: %s", info.name, exc)
                rt.pid = None
                continue
            adopted.append((rt, link, info, recent))
        # From here on nothing is awaited, so no event comes in between, and every process
        # has its state before any is found ready (which would start its start_on_ready).
        for rt, link, info, recent in adopted:
            self._adopt(rt, link, info, recent)
        for rt, _, info, _ in adopted:
            if rt.state != S.STARTED:
                continue
            if not rt.cfg.has_readiness:
                self._set(rt, S.READY, "re-attached (no readiness condition)")
                self._on_ready(rt, attached=True)
                continue
            if rt.cfg.ready_time is not None:
                left = rt.cfg.ready_time - (time.time() - info.started)
                if left > 0:
                    self._side(rt, self._ready_timer(rt, left))
                else:
                    rt.ready_time_passed = True
            self._check_ready(rt, attached=True)

    def apply_config(self, config: model.Config) -> dict[str, list[str]]:
        """Take a reloaded configuration: new processes are added (stopped), processes
        no longer configured are dropped once they are not running (running ones stay until
        stopped), changed ones get their new settings for their next start."""
        added, removed, changed, kept = [], [], [], []
        for name, cfg in config.processes.items():
            rt = self.procs.get(name)
            if rt is None:
                rt = Runtime(cfg, output=deque(maxlen=max(1, cfg.max_output_lines)))
                self.procs[name] = rt
                added.append(name)
            rt.removed = False
            if (rt.next_cfg or rt.cfg) == cfg:
                continue
            if name not in added:
                changed.append(name)
            rt.next_cfg = cfg
            if rt.state in STARTABLE:
                self._configure(rt)
        for name in list(self.procs):
            if name not in config.processes:
                if self.procs[name].state in STARTABLE:
                    del self.procs[name]
                    removed.append(name)
                else:
                    self.procs[name].removed = True
                    kept.append(name)
        self.states = {name: (self.states[name] if name in self.states
                              and self.states[name].cfg == st else StateRuntime(st))
                       for name, st in config.states.items()}
        self.config = config
        self._limiters.clear()
        return {"added": added, "removed": removed, "changed": changed,
                "removed_when_stopped": kept}

    def _configure(self, rt: Runtime) -> None:
        """Give rt the settings of the last reload (before it starts)."""
        cfg, rt.next_cfg = rt.next_cfg, None
        if cfg is None:
            return
        rt.cfg = cfg
        rt.regex = re.compile(cfg.ready_regex) if cfg.ready_regex is not None else None
        if rt.output.maxlen != max(1, cfg.max_output_lines):
            rt.output = deque(rt.output, maxlen=max(1, cfg.max_output_lines))

    async def shutdown(self) -> None:
        """Stop every process the configuration runs (dependents first), except those with
        the flag disable_stop and what they depend on, which are left running for the next
        manager."""
        keep: set[str] = set()
        todo = [name for name, rt in self.procs.items()
                if "disable_stop" in rt.cfg.flags and rt.state not in STARTABLE]
        while todo:
            name = todo.pop()
            if name in keep or name not in self.procs:
                continue
            keep.add(name)
            todo += self.procs[name].cfg.depends_on
        await asyncio.gather(*(self._stop(rt, "manager shutting down")
                               for name, rt in self.procs.items() if name not in keep))
        await self.close()

    async def close(self) -> None:
        """Forget the daemons without stopping anything (processes keep running)."""
        tasks = [t for rt in self.procs.values() for t in ([rt.task] if rt.task else [])]
        tasks += [t for rt in self.procs.values() for t in rt.side_tasks]
        tasks += list(self._event_tasks.values()) + list(self._bg)
        while tasks:
            for task in tasks:
                task.cancel()
            await asyncio.gather(*tasks, return_exceptions=True)
            tasks = list(self._bg)  # stops the cancellations started meanwhile
        with contextlib.suppress(ValueError):
            self.registry.listeners.remove(self._registry_changed)

    # ---- transitions ---------------------------------------------------------------------
    def _set(self, rt: Runtime, state: ProcState, reason: str = "") -> None:
        check_transition(rt.state, state)
        rt.state = state
        rt.reason = reason
        t = Transition(time.time(), state, reason)
        rt.transitions.append(t)
        if state == S.READY:
            rt.ready_at = time.monotonic()
            rt.ready_wall = t.time
        log.info("process %s: %s%s", rt.cfg.name, state.value, f" ({reason})" if reason else "")
        if rt.removed and state in STARTABLE and self.procs.get(rt.cfg.name) is rt:
            del self.procs[rt.cfg.name]  # removed by a reload while it ran
            log.info("process %s: removed (no longer configured)", rt.cfg.name)
        _tell(self.transition_listeners, rt.cfg.name, t)
        self._changed.notify()

    def _background(self, task: asyncio.Task[Any]) -> None:
        self._bg.add(task)
        task.add_done_callback(self._bg.discard)

    def _registry_changed(self) -> None:
        for rt in list(self.procs.values()):
            if rt.state == S.STARTED:
                self._check_ready(rt)
        self._changed.notify()

    # ---- starting ------------------------------------------------------------------------
    def _launch(self, rt: Runtime) -> asyncio.Task[None] | None:
        """Start rt's start task unless it runs or is up already."""
        if rt.task is not None and not rt.task.done():
            return rt.task
        if rt.state not in STARTABLE or self.procs.get(rt.cfg.name) is not rt:
            return None  # running, or removed by a reload
        self._configure(rt)
        self._cancel_side(rt)  # a pending restart: this start is it
        rt.stop_requested = rt.start_requested = False
        rt.watchdog_fired = None
        rt.ready_at = None  # the restart count looks at how long this run stays ready
        self._set(rt, S.STARTING)
        rt.task = asyncio.get_running_loop().create_task(self._start(rt))
        return rt.task

    async def _start(self, rt: Runtime) -> None:
        try:
            await self._dependencies(rt)
            await self._spawn(rt)
        except asyncio.CancelledError:
            if rt.state == S.STARTING:
                self._set(rt, S.STOPPED, "start cancelled")
            raise
        except StartError as exc:
            if rt.state == S.STARTING:
                self._set(rt, S.FAILED, str(exc))
                self._after_failure(rt)
        except Exception as exc:  # a bug, or a request the daemon client cannot encode
            log.exception("process %s: cannot start", rt.cfg.name)
            if rt.state == S.STARTING:
                self._set(rt, S.FAILED, f"cannot start: {exc}")
                self._after_failure(rt)

    async def _dependencies(self, rt: Runtime) -> None:
        jobs = []
        for dep in rt.cfg.depends_on:
            if dep in self.states:
                jobs.append(self._state_up(dep, rt.cfg.node))
            else:
                jobs.append(self._dependency_ready(rt, dep))
        jobs += [self._dependency_finished(rt, dep) for dep in rt.cfg.start_before]
        tasks = [asyncio.ensure_future(job) for job in jobs]
        try:
            if tasks:  # the first failure fails the start: no waiting for the others
                await asyncio.wait(tasks, return_when=asyncio.FIRST_EXCEPTION)
        finally:
            for task in tasks:
                task.cancel()
        errors = [task.exception() for task in tasks if task.done() and not task.cancelled()]
        for error in errors:
            if error is not None:
                raise error

    async def _dependency_ready(self, rt: Runtime, dep: str) -> None:
        d = self.procs.get(dep)
        if d is None:  # rt runs on with a configuration from before a reload
            raise StartError(f"dependency {dep} is no longer configured")
        if d.state not in (S.READY, S.STARTED):
            self._launch(d)
        try:
            await self.wait([dep], {S.READY}, fail_on={S.FAILED, S.FINISHED, S.STOPPED})
        except StartError as exc:
            raise StartError(f"dependency {dep} did not become ready: {exc}") from None

    async def _dependency_finished(self, rt: Runtime, dep: str) -> None:
        d = self.procs.get(dep)
        if d is None:
            raise StartError(f"{dep} (start_before) is no longer configured")
        if d.state == S.FINISHED:
            return
        if d.state in STARTABLE:
            self._launch(d)
        try:
            await self.wait([dep], {S.FINISHED}, fail_on={S.FAILED, S.STOPPED})
        except StartError as exc:
            raise StartError(f"{dep} (start_before) did not finish: {exc}") from None

    def _environment(self, cfg: model.Process) -> dict[str, str]:
        env = {k: os.environ[k] for k in BASE_ENV if k in os.environ}
        env.update({k: os.environ[k] for k in cfg.pass_environment if k in os.environ})
        if "forward_x11" in cfg.flags:  # the manager's X display
            env.update({k: os.environ[k] for k in X11_ENV if k in os.environ})
        env["LN_MANAGER"] = self.manager_address_for(cfg.node)
        env["LN_PROGRAM_NAME"] = cfg.name.replace("/", ".")
        if cfg.parameters:  # initial overrides of its parameter blocks (docs/parameters.md)
            from ..parameters.tools import to_json

            env["LN_PARAMETERS"] = to_json(cfg.parameters)
        dirs = cfg.message_definition_dirs + self.config.message_definition_dirs
        if dirs:
            env["LN_MESSAGE_DEFINITION_DIRS"] = ":".join(dirs)
        env.update(self.extra_env)
        env.update(cfg.environment)
        return env

    async def _spawn(self, rt: Runtime) -> None:
        cfg = rt.cfg
        await self._limiter(cfg.node).acquire()
        try:
            link = await self._link(cfg.node)
        except (OSError, self.backend.error_type) as exc:
            raise StartError(f"cannot start: {exc}") from None
        spec = self.backend.spawn_spec(**spawn_fields(cfg, self._environment(cfg)))
        # A record of an earlier run of this name would answer SPAWN with "exists".
        if rt.daemon_record:
            with contextlib.suppress(self.backend.error_type):
                await link.forget(cfg.name)
            rt.daemon_record = False
        # Reset before the spawn, not after: the new run's first output can be handled
        # before this task resumes with the daemon's answer.
        rt.regex_seen = rt.ready_time_passed = False
        rt.early_exit = None
        spawning = asyncio.ensure_future(link.spawn(spec))
        try:
            info = await asyncio.shield(spawning)
        except self.backend.error_type as exc:
            raise StartError(f"cannot start: {exc}") from None
        except asyncio.CancelledError:
            # Stopped while the daemon was starting it: let that finish, then stop it and
            # wait for its exit, so nothing runs that the scheduler believes stopped.  (Without
            # a stop request this is the scheduler closing: the process runs on.)
            if rt.stop_requested:
                with contextlib.suppress(Exception):
                    await self._stop_spawned(rt, link, await spawning)
            raise
        rt.pid = info.pid
        rt.link = link
        rt.daemon_record = True
        rt.started_at = time.time()
        rt.exit_code = rt.exit_signal = None
        early, rt.early_exit = rt.early_exit, None
        if rt.state != S.STARTING:  # stopped (or exited) while the spawn was on its way
            return
        if early is not None and early.pid == info.pid:  # it has already exited
            self._on_exit(rt, early.exit_code, early.signal)
            return
        if not cfg.has_readiness:
            self._set(rt, S.READY, "started (no readiness condition)")
            self._on_ready(rt)
            return
        self._set(rt, S.STARTED, f"pid {info.pid}")
        if cfg.ready_time is not None:
            self._side(rt, self._ready_timer(rt, cfg.ready_time))
        self._check_ready(rt)

    async def _stop_spawned(self, rt: Runtime, link: DaemonLink, info: ProcessInfo) -> None:
        """Stop the run the daemon started for rt while rt was being stopped (still
        `starting`); return once it has exited."""
        rt.pid, rt.link, rt.daemon_record = info.pid, link, True
        early, rt.early_exit = rt.early_exit, None
        if early is not None and early.pid == info.pid:
            rt.pid = None  # it has exited already
            return
        with contextlib.suppress(self.backend.error_type):  # it may have exited meanwhile
            await link.stop(rt.cfg.name)
        # its exit (_on_exit) or the connection's loss clears it
        await self._changed.wait_for(lambda: rt.pid != info.pid)

    async def _ready_timer(self, rt: Runtime, delay: float) -> None:
        await asyncio.sleep(delay)
        rt.ready_time_passed = True
        self._check_ready(rt)

    def _check_ready(self, rt: Runtime, *, attached: bool = False) -> None:
        """READY once every readiness condition of rt holds (`attached`: found so by a
        new manager)."""
        if rt.state != S.STARTED:
            return
        cfg = rt.cfg
        held = []
        if cfg.ready_regex is not None:
            if not rt.regex_seen:
                return
            held.append(f"output matched {cfg.ready_regex!r}")
        if cfg.ready_time is not None:
            if not rt.ready_time_passed:
                return
            held.append(f"{cfg.ready_time:g} s passed")
        if cfg.ready_on_topic is not None:
            if self.registry.topic_publishers(cfg.ready_on_topic) == 0:
                return
            held.append(f"topic {cfg.ready_on_topic} has a publisher")
        if cfg.ready_on_service is not None:
            if not self.registry.service_provided(cfg.ready_on_service):
                return
            held.append(f"service {cfg.ready_on_service} is registered")
        self._set(rt, S.READY, ", ".join(held))
        self._on_ready(rt, attached=attached)

    def _on_ready(self, rt: Runtime, *, attached: bool = False) -> None:
        """Its start_on_ready (unless it was found ready: the manager before did that, or
        they were stopped since), its watchdog, the dependents its loss stopped."""
        for name in [] if attached else rt.cfg.start_on_ready:
            if name in self.procs:
                self._launch(self.procs[name])
        if rt.cfg.watchdog is not None:
            self._side(rt, self._watchdog(rt, rt.cfg.watchdog))
        # dependents this process's earlier loss stopped come back with it
        for other in self.procs.values():
            if other.stopped_for == rt.cfg.name and other.state in STARTABLE:
                other.stopped_for = None
                self._launch(other)

    def _side(self, rt: Runtime, coro: Awaitable[None]) -> asyncio.Task[None]:
        task = asyncio.get_running_loop().create_task(coro)  # type: ignore[arg-type]
        rt.side_tasks.add(task)
        task.add_done_callback(rt.side_tasks.discard)
        return task

    def _cancel_side(self, rt: Runtime) -> None:
        current = asyncio.current_task()
        for task in list(rt.side_tasks):
            if task is not current:
                task.cancel()

    # ---- states (check/up/down commands) -------------------------------------------------
    async def _state_up(self, name: str, node: str) -> None:
        st = self.states[name]
        node = st.cfg.node or node
        async with st.lock:
            fresh = time.monotonic() - st.checked_at < st.cfg.min_check_interval
            if st.up and fresh:
                return
            if await self._run_check(st, node):
                return
            if st.cfg.up is None:
                raise StartError(f"state {name} is DOWN (check failed) and has no up command")
            code = await self._run_transient(node, f"{name}.up", st.cfg.up)
            if code != 0 or not await self._run_check(st, node):
                raise StartError(f"state {name} stays DOWN after its up command "
                                 f"(exit status {code})")

    async def _run_check(self, st: StateRuntime, node: str) -> bool:
        code = await self._run_transient(node, f"{st.cfg.name}.check", st.cfg.check)
        st.up = code == 0
        st.checked_at = time.monotonic()
        log.info("state %s: %s", st.cfg.name, "UP" if st.up else "DOWN")
        return st.up

    async def _run_transient(self, node: str, label: str, command: str) -> int | None:
        """Run a shell command on `node` through its daemon; its exit status (None if it
        died by a signal)."""
        self._transient += 1
        name = f"state:{label}:{self._transient}"
        try:
            link = await self._link(node)
        except (OSError, self.backend.error_type) as exc:
            raise StartError(f"{label}: {exc}") from None
        future: asyncio.Future[Exited] = asyncio.get_running_loop().create_future()
        self._waiters[name] = (future, link)
        env = {k: os.environ[k] for k in BASE_ENV if k in os.environ}
        env["LN_MANAGER"] = self.manager_address_for(node)
        spec = self.backend.spawn_spec(name=name, command=command, shell=True, env=env,
                                       use_pty=False, max_output_lines=100)
        try:
            await link.spawn(spec)
            exited = await future
        except self.backend.error_type as exc:
            raise StartError(f"{label}: cannot run {command!r}: {exc}") from None
        finally:
            self._waiters.pop(name, None)
        with contextlib.suppress(self.backend.error_type):
            await link.forget(name)
        return exited.exit_code

    # ---- stopping ------------------------------------------------------------------------
    def _dependents(self, name: str) -> list[Runtime]:
        return [rt for rt in self.procs.values() if name in rt.cfg.depends_on]

    def _stopped_with(self, rt: Runtime) -> list[Runtime]:
        """The dependents that go down when rt does: none with `dont_stop_dependent_procs`."""
        if "dont_stop_dependent_procs" in rt.cfg.flags:
            return []
        return self._dependents(rt.cfg.name)

    async def _stop(self, rt: Runtime, reason: str, *, force: bool = False,
                    restore: bool = False) -> None:
        """Stop rt, dependents first.  `restore`: it is stopped because a dependency went
        down (rt.stopped_for) and comes back with it, and so do its dependents; any other
        stop keeps it down whatever its dependencies do."""
        if "disable_stop" in rt.cfg.flags and not force and reason == "stopped by request":
            raise StartError(f"{rt.cfg.name} has the flag disable_stop")
        if not restore:
            rt.stopped_for = None
            rt.start_requested = False
        rt.stop_requested = True  # before its dependents stop: they must not come back yet
        # dependents first (again if one was started meanwhile, on rt still up)
        while dependents := [d for d in self._stopped_with(rt) if d.state not in STARTABLE]:
            if restore:
                for d in dependents:
                    d.stopped_for = rt.cfg.name
            await asyncio.gather(*(self._stop(d, f"dependency {rt.cfg.name} stopped",
                                              force=force, restore=restore)
                                   for d in dependents))
        self._cancel_side(rt)
        if rt.task is not None and not rt.task.done() and rt.task is not asyncio.current_task():
            rt.task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await rt.task
        if rt.state == S.STARTING:
            self._set(rt, S.STOPPED, reason)
        if rt.state in STARTABLE:
            self._restore(rt)
        if rt.state in (S.STARTED, S.READY):
            self._set(rt, S.STOPPING, reason)
            try:
                await (await self._link(rt.cfg.node)).stop(rt.cfg.name)
            except (OSError, self.backend.error_type) as exc:
                log.warning("process %s: stop failed: %s", rt.cfg.name, exc)
        if rt.state == S.STOPPING:
            # not "until stopped": a restored dependent may be starting again at once
            await self._changed.wait_for(lambda: rt.state != S.STOPPING)

    # ---- daemon events -------------------------------------------------------------------
    def _on_event(self, event: DaemonEvent) -> None:
        if isinstance(event, self.backend.output_type):
            rt = self.procs.get(event.name)
            if rt is None:
                return
            rt.output.append(event)
            _tell(self.output_listeners, event.name, event)
            if rt.regex is not None and not rt.regex_seen and rt.regex.search(event.text):
                rt.regex_seen = True
                self._check_ready(rt)
        elif isinstance(event, self.backend.exited_type):
            waiter, _ = self._waiters.get(event.name, (None, None))
            if waiter is not None and not waiter.done():
                waiter.set_result(event)
                return
            rt = self.procs.get(event.name)
            if rt is None:
                return
            if rt.pid == event.pid:
                self._on_exit(rt, event.exit_code, event.signal)
            elif rt.state == S.STARTING:
                rt.early_exit = event  # the spawn answer is still on its way

    def _on_exit(self, rt: Runtime, code: int | None, sig: int | None) -> None:
        rt.exit_code, rt.exit_signal = code, sig
        rt.pid = None
        self._cancel_side(rt)
        if rt.state not in ALIVE and rt.state != S.STARTING:
            return
        how = (f"exit status {code}" if sig is None
               else f"killed by {signal.Signals(sig).name if sig in _SIGNALS else sig}")
        if rt.stop_requested:
            self._set(rt, S.STOPPED, f"{rt.reason or 'stopped'}; {how}")
            self._restore(rt)
            return
        if rt.watchdog_fired is not None:
            why, rt.watchdog_fired = rt.watchdog_fired, None
            self._set(rt, S.FAILED, f"{why}; {how}")
            self._lost_dependency(rt)
            self._schedule_restart(rt)
            return
        if rt.state == S.STARTING:  # exited before the spawn answer was processed
            self._set(rt, S.STARTED, "")
        if (code == 0 and sig is None) or "no_error_on_stop" in rt.cfg.flags:
            self._set(rt, S.FINISHED, how)
            failed = False
        else:
            self._set(rt, S.FAILED, how)
            failed = True
        self._lost_dependency(rt)
        restart = rt.cfg.restart
        if restart == model.Restart.ALWAYS or (restart == model.Restart.ON_FAILURE and failed):
            self._schedule_restart(rt)

    def _after_failure(self, rt: Runtime) -> None:
        if rt.cfg.restart != model.Restart.NEVER and not rt.stop_requested:
            self._schedule_restart(rt)

    def _restore(self, rt: Runtime) -> None:
        """A process asked to start while it was stopping starts now.  A dependent stopped
        because its dependency went down comes back as soon as the dependency is ready again
        (which may already be the case when its stop completes)."""
        if rt.start_requested and rt.state in STARTABLE:
            self._launch(rt)
            return
        dep = self.procs.get(rt.stopped_for) if rt.stopped_for else None
        if dep is not None and dep.state == S.READY and not dep.stop_requested \
                and rt.state in STARTABLE:
            rt.stopped_for = None
            self._launch(rt)

    def _lost_dependency(self, rt: Runtime) -> None:
        """Dependents of a process that went down are stopped (and come back with it)."""
        for d in self._stopped_with(rt):
            if d.state not in STARTABLE:
                d.stopped_for = rt.cfg.name
                self._background(asyncio.get_running_loop().create_task(
                    self._stop(d, f"dependency {rt.cfg.name} went down", restore=True)))

    def _schedule_restart(self, rt: Runtime) -> None:
        if rt.ready_at is not None and time.monotonic() - rt.ready_at >= STABLE_AFTER:
            rt.restarts = 0
        if rt.restarts >= rt.cfg.restart_limit:
            reason = f"gave up after {rt.restarts} restarts; last: {rt.reason}"
            rt.reason = reason
            t = Transition(time.time(), rt.state, reason)
            rt.transitions.append(t)
            log.warning("process %s: %s", rt.cfg.name, reason)
            _tell(self.transition_listeners, rt.cfg.name, t)
            self._changed.notify()
            return
        # (2 ** restarts no longer fits a float after 1023 restarts)
        delay = min(MAX_RESTART_DELAY, rt.cfg.restart_delay * 2.0 ** min(rt.restarts, 1000))
        rt.restarts += 1
        log.info("process %s: restart %d of %d in %.3g s", rt.cfg.name, rt.restarts,
                 rt.cfg.restart_limit, delay)
        rt.restart_task = self._side(rt, self._restart_later(rt, delay))
        rt.restart_task.add_done_callback(lambda _: self._changed.notify())  # final if cancelled

    async def _restart_later(self, rt: Runtime, delay: float) -> None:
        await asyncio.sleep(delay)
        if rt.state in STARTABLE and not rt.stop_requested:
            self._launch(rt)

    async def _watchdog(self, rt: Runtime, wd: model.Watchdog) -> None:
        window = max(1.0, 3.0 / wd.min_hz)
        before = await self.registry.topic_published(wd.topic)
        while rt.state == S.READY:
            await asyncio.sleep(window)
            now = await self.registry.topic_published(wd.topic)
            rate = (now - before) / window
            before = now
            if rate < wd.min_hz and rt.state == S.READY:
                why = f"watchdog: {wd.topic} at {rate:.3g} Hz < {wd.min_hz:g} Hz"
                log.warning("process %s: %s: restarting", rt.cfg.name, why)
                rt.watchdog_fired = why
                self._set(rt, S.STOPPING, why)
                try:
                    await (await self._link(rt.cfg.node)).stop(rt.cfg.name)
                except (OSError, self.backend.error_type) as exc:
                    log.warning("process %s: stop failed: %s", rt.cfg.name, exc)
                return  # its exit is a failure that restarts it (_on_exit)

    # ---- daemons -------------------------------------------------------------------------
    async def _link(self, node: str) -> DaemonLink:
        link = await self.backend.link(node)
        if id(link) not in self._event_tasks:
            self._event_tasks[id(link)] = asyncio.get_running_loop().create_task(
                self._pump(link, node))
        return link

    async def _pump(self, link: DaemonLink, node: str) -> None:
        queue = link.events()
        while True:
            event = await queue.get()
            if event is None:  # the connection ended
                self._event_tasks.pop(id(link), None)
                self._daemon_lost(link, node)
                return
            try:
                self._on_event(event)
            except Exception:  # one bad event must not stop supervision
                log.exception("handling daemon event %r", event)

    def _daemon_lost(self, link: DaemonLink, node: str) -> None:
        """The daemon connection `link` (first used for `node`) ended: what ran through it is
        unknown now.  Those processes fail (and restart by their policy, through a new
        connection)."""
        for rt in list(self.procs.values()):
            if rt.link is link and rt.pid is not None and rt.state == S.STARTING:
                rt.pid = None  # being stopped while it was spawned (_stop_spawned)
                self._changed.notify()
            if rt.state in ALIVE and rt.link is link:
                rt.pid = None
                self._cancel_side(rt)
                if rt.stop_requested:
                    self._set(rt, S.STOPPED, "stopped (daemon connection lost)")
                    self._restore(rt)
                    continue
                self._set(rt, S.FAILED, f"lost the connection to the ln_daemon of node "
                                        f"{rt.cfg.node!r}")
                self._lost_dependency(rt)
                if rt.cfg.restart != model.Restart.NEVER:
                    self._schedule_restart(rt)
        for future, used in self._waiters.values():
            if used is link and not future.done():
                future.set_exception(StartError(f"lost the ln_daemon of node {node!r}"))

    def _limiter(self, node: str) -> RateLimiter:
        host = self.config.node_map.get(node, node)
        if host not in self._limiters:
            h = self.config.hosts.get(host)
            self._limiters[host] = RateLimiter(h.process_start_rate_limit if h else None)
        return self._limiters[host]

    def _adopt(self, rt: Runtime, link: DaemonLink, info: ProcessInfo,
               recent: list[OutputLine]) -> None:
        """rt as the daemon has it: `started` (readiness is checked by the caller), or
        exited (before or while this scheduler attached)."""
        rt.link = link
        newer = [line for line in rt.output if not recent or line.time > recent[-1].time]
        rt.output.clear()
        rt.output.extend(recent)
        rt.output.extend(newer)  # came as events while attaching
        rt.started_at = info.started
        running = info.state in ("running", "stopping")
        if running and rt.pid == info.pid:
            if rt.regex is not None:
                rt.regex_seen = rt.regex_seen or any(rt.regex.search(line.text)
                                                     for line in recent)
            self._set(rt, S.STARTED, f"re-attached to pid {info.pid}")
            return
        if not running:
            rt.exit_code, rt.exit_signal = info.exit_code, info.signal
        # else it exited while attaching: _on_exit kept its status
        ok = rt.exit_code == 0 and rt.exit_signal is None
        self._set(rt, S.FINISHED if ok else S.FAILED,
                  f"exited while no manager was attached (exit status {rt.exit_code}, "
                  f"signal {rt.exit_signal})")

    # ---- groups ----------------------------------------------------------------------------
    def _group_members(self, group: str, out: list[str], seen: set[str]) -> None:
        if group in seen:
            return
        seen.add(group)
        for member in self.config.groups[group].members:
            if member in self.procs and member not in out:
                out.append(member)
            elif member in self.config.groups:
                self._group_members(member, out, seen)


def _tell(listeners: list[Callable[..., None]], *args: Any) -> None:
    """Call every listener; one that raises must not stop the others or the scheduler."""
    for listener in list(listeners):
        try:
            listener(*args)
        except Exception:
            log.exception("listener %r failed", listener)


_SIGNALS = {int(s) for s in signal.Signals}
