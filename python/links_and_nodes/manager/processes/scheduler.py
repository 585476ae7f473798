"""The scheduler: brings the processes of a loaded configuration up in dependency order,
gated on real readiness, keeps them supervised and takes them down dependents first.  It
holds one `ManagedProcess` (managed.py: spawn, readiness, exit, restart policy, watchdog) per
configured process and keeps what spans them: the dependency graph, the configuration's
states (state_commands.py) and one event pump per ln_daemon connection.  It asks the
manager's registry (core.Core) whether topics have publishers and services are registered.
States and transitions: states.py; the rules: docs/process_management.md.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable, Iterable
from typing import Any

from ..config import model
from .backend import Backend, DaemonEvent, DaemonLink, Registry, StartError
from .changes import Changes
from .daemon_resources import ResourceSample
from .daemon_wire import OutputLine, ProcessInfo, SpawnSpec
from .managed import ManagedProcess, Pending, Transition
from .output_levels import output_level, process_finder
from .resources import Resources
from .spawning import RateLimiter, RateLimiters, environment, spawn_fields
from .state_commands import StateCommands, StateRuntime
from .states import STARTABLE, ProcState

__all__ = ["Backend", "DaemonEvent", "DaemonLink", "ManagedProcess", "Pending",
           "RateLimiter", "Registry", "Scheduler", "StartError", "StateRuntime",
           "Transition", "spawn_fields"]

log = logging.getLogger("ln_manager")

S = ProcState


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
        self.procs: dict[str, ManagedProcess] = {
            name: ManagedProcess(cfg, self) for name, cfg in config.processes.items()}
        self.state_commands = StateCommands(config, backend, self.link,
                                            self.manager_address_for)
        self.changed = Changes()
        self._limiters = RateLimiters(lambda: self.config)
        self._event_tasks: dict[int, asyncio.Task[None]] = {}
        self._bg: set[asyncio.Task[Any]] = set()  # stops of dependents
        self.resources = Resources()  # the newest resource samples of hosts and processes
        self.output_listeners: list[Callable[[str, OutputLine], None]] = []
        self.transition_listeners: list[Callable[[str, Transition], None]] = []
        registry.listeners.append(self._registry_changed)
        if getattr(registry, "logs", None) is not None:  # which process a logging client is
            registry.logs.process_of = process_finder(self.procs)  # type: ignore[attr-defined]

    @property
    def states(self) -> dict[str, StateRuntime]:
        """The configuration's states (check/up commands), by name."""
        return self.state_commands.states

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
            self.procs[name].ask_start()
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
            proc = self.procs.get(name)
            if proc is not None:  # not removed by a reload meanwhile
                proc.restarts = 0
                proc.launch()
        return names

    async def wait(self, names: Iterable[str], states: set[ProcState],
                   timeout: float | None = None, *, fail_on: set[ProcState] | None = None,
                   final: bool = False) -> None:
        """Until every process of `names` is in one of `states`; StartError if one reaches
        `fail_on` first (its reason; with `final` only if no restart of it is pending),
        TimeoutError after `timeout` seconds."""
        procs = [self.procs[n] for n in names]
        fail_on = fail_on or set()

        def done() -> bool:
            for p in procs:
                if p.state in fail_on and p.state not in states and not (
                        final and p.restart_task is not None and not p.restart_task.done()):
                    raise StartError(f"{p.cfg.name}: {p.state.value}: {p.reason}")
            return all(p.state in states for p in procs)

        if not done():  # (a timeout of 0 only looks)
            await asyncio.wait_for(self.changed.wait_for(done), timeout)

    async def wait_ready(self, target: str = "all", timeout: float | None = None, *,
                         final: bool = False) -> None:
        """Until every process of `target` is ready (or finished, for ones that ran to
        completion); StartError as soon as one fails (`final`: fails for good, with no
        restart pending)."""
        await self.wait(self.targets(target), {S.READY, S.FINISHED}, timeout,
                        fail_on={S.FAILED}, final=final)

    def status(self) -> list[dict[str, Any]]:
        return [{**p.as_dict(), **self.resources.process_fields(name, p.pid)}
                for name, p in self.procs.items()]

    def history(self, name: str) -> list[Transition]:
        return list(self.procs[name].transitions)

    def output(self, name: str, n: int = 100) -> list[OutputLine]:
        lines = list(self.procs[name].output)
        return lines[-n:] if n > 0 else []

    async def attach(self) -> None:
        """Take over processes a daemon still runs for this instance (a new manager after
        the old one died): their true states and recent output."""
        found: list[tuple[ManagedProcess, DaemonLink, ProcessInfo]] = []
        for node in sorted({p.cfg.node for p in self.procs.values()}):
            try:
                link = await self.link(node)
                infos = await link.list()
            except (OSError, self.backend.error_type) as exc:
                log.warning("cannot ask the daemon of node %r for its processes: %s", node, exc)
                continue
            for info in infos:
                proc = self.procs.get(info.name)
                if proc is None or proc.cfg.node != node or proc.state != S.STOPPED:
                    continue
                proc.daemon_record = True
                if info.state in ("running", "stopping"):
                    proc.pid = info.pid  # an exit from now on clears it (on_exit)
                found.append((proc, link, info))
        adopted = []
        for proc, link, info in found:
            try:
                recent = await link.output(info.name, proc.cfg.max_output_lines)
            except (OSError, self.backend.error_type) as exc:
                log.warning("process %s: cannot re-attach: %s", info.name, exc)
                proc.pid = None
                continue
            adopted.append((proc, link, info, recent))
        # From here on nothing is awaited, so no event comes in between, and every process
        # has its state before any is found ready (which would start its start_on_ready).
        for proc, link, info, recent in adopted:
            proc.adopt(link, info, recent)
        for proc, _, info, _ in adopted:
            proc.resume(info)

    def apply_config(self, config: model.Config) -> dict[str, list[str]]:
        """Take a reloaded configuration: new processes are added (stopped), processes
        no longer configured are dropped once they are not running (running ones stay until
        stopped), changed ones get their new settings for their next start."""
        added, removed, changed, kept = [], [], [], []
        for name, cfg in config.processes.items():
            proc = self.procs.get(name)
            if proc is None:
                proc = self.procs[name] = ManagedProcess(cfg, self)
                added.append(name)
            proc.removed = False
            if (proc.next_cfg or proc.cfg) == cfg:
                continue
            if name not in added:
                changed.append(name)
            proc.next_cfg = cfg
            if proc.state in STARTABLE:
                proc.configure()
        for name in list(self.procs):
            if name not in config.processes:
                if self.procs[name].state in STARTABLE:
                    del self.procs[name]
                    removed.append(name)
                else:
                    self.procs[name].removed = True
                    kept.append(name)
        self.state_commands.configure(config)
        self.config = config
        self._limiters.clear()
        return {"added": added, "removed": removed, "changed": changed,
                "removed_when_stopped": kept}

    async def shutdown(self) -> None:
        """Stop every process the configuration runs (dependents first), except those with
        the flag disable_stop and what they depend on, which are left running for the next
        manager."""
        keep: set[str] = set()
        todo = [name for name, p in self.procs.items()
                if "disable_stop" in p.cfg.flags and p.state not in STARTABLE]
        while todo:
            name = todo.pop()
            if name in keep or name not in self.procs:
                continue
            keep.add(name)
            todo += self.procs[name].cfg.depends_on
        await asyncio.gather(*(self._stop(p, "manager shutting down")
                               for name, p in self.procs.items() if name not in keep))
        await self.close()

    async def close(self) -> None:
        """Forget the daemons without stopping anything (processes keep running)."""
        tasks = [p.task for p in self.procs.values() if p.task]
        tasks += [t for p in self.procs.values() for t in p.side_tasks]
        tasks += list(self._event_tasks.values()) + list(self._bg)
        while tasks:
            for task in tasks:
                task.cancel()
            await asyncio.gather(*tasks, return_exceptions=True)
            tasks = list(self._bg)  # stops the cancellations started meanwhile
        with contextlib.suppress(ValueError):
            self.registry.listeners.remove(self._registry_changed)

    # ---- what a ManagedProcess asks of it (managed.Owner) --------------------------------
    def is_current(self, proc: ManagedProcess) -> bool:
        return self.procs.get(proc.cfg.name) is proc

    def transitioned(self, proc: ManagedProcess, t: Transition) -> None:
        if proc.removed and t.state in STARTABLE and self.is_current(proc):
            del self.procs[proc.cfg.name]  # removed by a reload while it ran
            log.info("process %s: removed (no longer configured)", proc.cfg.name)
        _tell(self.transition_listeners, proc.cfg.name, t)
        self.changed.notify()

    async def admit(self, node: str) -> None:
        await self._limiters.for_node(node).acquire()

    def spawn_request(self, cfg: model.Process) -> SpawnSpec:
        env = environment(cfg, self.config, self.manager_address_for(cfg.node), self.extra_env)
        return self.backend.spawn_spec(**spawn_fields(cfg, env))

    def became_ready(self, proc: ManagedProcess, attached: bool) -> None:
        """Its start_on_ready (unless it was found ready: the manager before did that, or
        they were stopped since), and the dependents its loss stopped."""
        for name in [] if attached else proc.cfg.start_on_ready:
            if name in self.procs:
                self.procs[name].launch()
        for other in list(self.procs.values()):
            if other.returns_with == proc.cfg.name and other.state in STARTABLE:
                other.launch()

    def may_return_with(self, dependency: str) -> bool:
        dep = self.procs.get(dependency)
        return dep is not None and dep.state == S.READY and not dep.stop_asked

    def went_down(self, proc: ManagedProcess) -> None:
        """Dependents of a process that went down are stopped (and come back with it)."""
        for d in self._stopped_with(proc):
            if d.state not in STARTABLE:
                self._background(asyncio.get_running_loop().create_task(
                    self._stop(d, f"dependency {proc.cfg.name} went down",
                               returns_with=proc.cfg.name)))

    async def dependencies(self, proc: ManagedProcess) -> None:
        """Until every dependency of proc is up; the first failure raises StartError."""
        jobs = []
        for dep in proc.cfg.depends_on:
            if dep in self.states:
                jobs.append(self.state_commands.up(dep, proc.cfg.node))
            else:
                jobs.append(self._dependency_ready(dep))
        jobs += [self._dependency_finished(dep) for dep in proc.cfg.start_before]
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

    async def _dependency_ready(self, dep: str) -> None:
        d = self.procs.get(dep)
        if d is None:  # the process runs on with a configuration from before a reload
            raise StartError(f"dependency {dep} is no longer configured")
        if d.state not in (S.READY, S.STARTED):
            d.launch()
        try:
            await self.wait([dep], {S.READY}, fail_on={S.FAILED, S.FINISHED, S.STOPPED})
        except StartError as exc:
            raise StartError(f"dependency {dep} did not become ready: {exc}") from None

    async def _dependency_finished(self, dep: str) -> None:
        d = self.procs.get(dep)
        if d is None:
            raise StartError(f"{dep} (start_before) is no longer configured")
        if d.state == S.FINISHED:
            return
        if d.state in STARTABLE:
            d.launch()
        try:
            await self.wait([dep], {S.FINISHED}, fail_on={S.FAILED, S.STOPPED})
        except StartError as exc:
            raise StartError(f"{dep} (start_before) did not finish: {exc}") from None

    # ---- the dependency graph ------------------------------------------------------------
    def _dependents(self, name: str) -> list[ManagedProcess]:
        return [p for p in self.procs.values() if name in p.cfg.depends_on]

    def _stopped_with(self, proc: ManagedProcess) -> list[ManagedProcess]:
        """The dependents that go down when proc does: none with `dont_stop_dependent_procs`."""
        if "dont_stop_dependent_procs" in proc.cfg.flags:
            return []
        return self._dependents(proc.cfg.name)

    async def _stop(self, proc: ManagedProcess, reason: str, *, force: bool = False,
                    returns_with: str | None = None) -> None:
        """Stop proc, dependents first.  `returns_with`: it is stopped because that
        dependency went down and comes back with it, and so do its dependents; any other
        stop keeps it down whatever its dependencies do."""
        if "disable_stop" in proc.cfg.flags and not force and reason == "stopped by request":
            raise StartError(f"{proc.cfg.name} has the flag disable_stop")
        # before its dependents stop: they must not come back yet
        proc.ask_stop(returns_with)
        # dependents first (again if one was started meanwhile, on proc still up)
        while dependents := [d for d in self._stopped_with(proc) if d.state not in STARTABLE]:
            await asyncio.gather(*(
                self._stop(d, f"dependency {proc.cfg.name} stopped", force=force,
                           returns_with=proc.cfg.name if returns_with else None)
                for d in dependents))
        await proc.stop(reason)

    # ---- daemons -------------------------------------------------------------------------
    async def link(self, node: str) -> DaemonLink:
        """The daemon connection of a node, with its events pumped."""
        link = await self.backend.link(node)
        if id(link) not in self._event_tasks:
            self._event_tasks[id(link)] = asyncio.get_running_loop().create_task(
                self._pump(link, node))
            self._background(asyncio.get_running_loop().create_task(
                self._ask_resources(link, node)))
        return link

    async def _ask_resources(self, link: DaemonLink, node: str) -> None:
        """Resource samples from a new daemon connection, at the daemon's default period."""
        ask = getattr(link, "resources", None)  # (a test's stand-in may have none)
        if ask is None:
            return
        try:
            await ask()
        except (OSError, self.backend.error_type) as exc:
            log.info("no resource samples from the ln_daemon of node %r: %s", node, exc)

    async def _pump(self, link: DaemonLink, node: str) -> None:
        queue = link.events()
        while True:
            event = await queue.get()
            if event is None:  # the connection ended
                self._event_tasks.pop(id(link), None)
                self._daemon_lost(link, node)
                return
            try:
                if isinstance(event, ResourceSample):
                    self._on_resources(event, id(link))
                else:
                    self._on_event(event)
            except Exception:  # one bad event must not stop supervision
                log.exception("handling daemon event %r", event)

    def _log_line(self, proc: ManagedProcess, line: OutputLine) -> None:
        """An output line that the process's log_level_regex matches, into the log store."""
        found = output_level(proc.cfg.log_level_regex, line.text)
        logs = getattr(self.registry, "logs", None)
        if found is None or logs is None:
            return
        logs.add(time_ns=int(line.time * 1e9), level=found[0], source="output",
                 client=proc.cfg.name, process=proc.cfg.name, host=proc.cfg.node,
                 pid=proc.pid or 0, file=line.stream, text=found[1])

    def _on_event(self, event: DaemonEvent) -> None:
        if isinstance(event, self.backend.output_type):
            proc = self.procs.get(event.name)
            if proc is None:
                return
            proc.output.append(event)
            _tell(self.output_listeners, event.name, event)
            self._log_line(proc, event)
            proc.saw_line(event)
        elif isinstance(event, self.backend.exited_type):
            if self.state_commands.exited(event):
                return
            proc = self.procs.get(event.name)
            if proc is not None:
                proc.exited(event)

    def _on_resources(self, sample: ResourceSample, source: int) -> None:
        """A sample from the daemon connection `source` (an id)."""
        self.resources.take(sample, source)
        for p in sample.processes:
            proc = self.procs.get(p.name)
            if proc is not None and proc.pid == p.pid:
                proc.resources(p)

    def _daemon_lost(self, link: DaemonLink, node: str) -> None:
        """The daemon connection `link` (first used for `node`) ended: what ran through it is
        unknown now.  Those processes fail (and restart by their policy, through a new
        connection)."""
        for proc in list(self.procs.values()):
            proc.daemon_lost(link)
        self.state_commands.daemon_lost(link, node)

    # ---- the rest ------------------------------------------------------------------------
    def _background(self, task: asyncio.Task[Any]) -> None:
        self._bg.add(task)
        task.add_done_callback(self._bg.discard)

    def _registry_changed(self) -> None:
        for proc in list(self.procs.values()):
            if proc.state == S.STARTED:
                proc.check_ready()
        self.changed.notify()

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
