"""A stand-in for ln_daemon in the scheduler's unit tests: the same calls as
daemon_client.DaemonClient, carried out with asyncio subprocesses in the test's own
process, plus a registry with topics and services the test sets.  Lets the scheduler's
ordering, readiness, restart and watchdog rules be tested without the C++ daemon."""

from __future__ import annotations

import asyncio
import contextlib
import os
import shlex
import signal
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from links_and_nodes.manager.processes import daemon_wire as dw
from links_and_nodes.manager.processes.scheduler import Backend


class FakeError(Exception):
    pass


# The daemon client's own request and event types, so the fake speaks exactly its API.
Spec = dw.SpawnSpec
Info = dw.ProcessInfo
Line = dw.OutputLine
Exit = dw.Exited


@dataclass
class _Proc:
    spec: Spec
    proc: asyncio.subprocess.Process
    started: float
    lines: deque[Line]
    exited: Exit | None = None


class FakeDaemon:
    def __init__(self) -> None:
        self.procs: dict[str, _Proc] = {}
        self.queue: asyncio.Queue[object] = asyncio.Queue()
        self.spawned: list[str] = []  # names in spawn order
        self.stops: list[str] = []  # names in the order STOP was asked for
        self.fail_spawn: set[str] = set()
        # names whose spawn answer comes only after the process's output and exit events
        self.late_answer: set[str] = set()

    def events(self) -> asyncio.Queue[object]:
        return self.queue

    async def spawn(self, spec: Spec) -> Info:
        if spec.name in self.fail_spawn:
            raise FakeError(f"{spec.name}: command not found")
        if spec.name in self.procs and self.procs[spec.name].exited is None:
            raise FakeError(f"{spec.name} exists")
        argv = ["/bin/sh", "-c", spec.command] if spec.shell else shlex.split(spec.command)
        proc = await asyncio.create_subprocess_exec(
            *argv, env=spec.env, cwd=spec.cwd, stdout=asyncio.subprocess.PIPE,
            stderr=asyncio.subprocess.STDOUT, start_new_session=True)
        p = _Proc(spec, proc, time.time(), deque(maxlen=spec.max_output_lines))
        self.procs[spec.name] = p
        self.spawned.append(spec.name)
        watch = asyncio.get_running_loop().create_task(self._watch(p))
        if spec.name in self.late_answer:
            # answer only after the first output (or the exit) went to the scheduler
            while not (p.lines or watch.done()) or not self.queue.empty():
                await asyncio.sleep(0.001)
            if not watch.done():
                await asyncio.sleep(0.01)  # and maybe the exit too
        return Info(spec.name, proc.pid, "running", None, None, p.started)

    async def _watch(self, p: _Proc) -> None:
        assert p.proc.stdout is not None
        async for raw in p.proc.stdout:
            line = Line(p.spec.name, "stdout", raw.decode(errors="replace").rstrip("\n"),
                        time.time())
            p.lines.append(line)
            await self.queue.put(line)
        rc = await p.proc.wait()
        code, sig = (rc, None) if rc >= 0 else (None, -rc)
        p.exited = Exit(p.spec.name, p.proc.pid, code, sig, time.time())
        await self.queue.put(p.exited)

    async def stop(self, name: str) -> None:
        self.stops.append(name)
        p = self.procs.get(name)
        if p is None or p.exited is not None:
            raise FakeError(f"{name} is not running")
        with contextlib.suppress(ProcessLookupError):
            os.killpg(p.proc.pid, p.spec.term_signal)

        async def kill_later() -> None:
            await asyncio.sleep(p.spec.term_timeout)
            if p.exited is None:
                with contextlib.suppress(ProcessLookupError):
                    os.killpg(p.proc.pid, signal.SIGKILL)
        asyncio.get_running_loop().create_task(kill_later())

    async def list(self) -> list[Info]:
        return [Info(n, p.proc.pid, "exited" if p.exited else "running",
                     p.exited.exit_code if p.exited else None,
                     p.exited.signal if p.exited else None, p.started)
                for n, p in self.procs.items()]

    async def output(self, name: str, n: int = 100) -> list[Line]:
        await asyncio.sleep(0)  # an answer takes a while: events may come first
        p = self.procs.get(name)
        return list(p.lines)[-n:] if p else []

    async def forget(self, name: str) -> None:
        p = self.procs.get(name)
        if p is not None and p.exited is not None:
            del self.procs[name]

    async def kill_all(self) -> None:
        for p in self.procs.values():
            if p.exited is None:
                with contextlib.suppress(ProcessLookupError):
                    os.killpg(p.proc.pid, signal.SIGKILL)
        for p in list(self.procs.values()):
            with contextlib.suppress(ProcessLookupError):
                await p.proc.wait()


class FakeRegistry:
    def __init__(self) -> None:
        self.listeners: list[Callable[[], None]] = []
        self.publishers: dict[str, int] = {}
        self.published: dict[str, int] = {}
        self.services: set[str] = set()

    def changed(self) -> None:
        for listener in list(self.listeners):
            listener()

    def topic_publishers(self, name: str) -> int:
        return self.publishers.get(name, 0)

    async def topic_published(self, name: str) -> int:
        return self.published.get(name, 0)

    def service_provided(self, name: str) -> bool:
        return name in self.services


def backend(daemon: FakeDaemon) -> Backend:
    async def link(node: str) -> FakeDaemon:
        return daemon
    return Backend(link=link, spawn_spec=Spec, exited_type=Exit, output_type=Line,
                   error_type=FakeError)
