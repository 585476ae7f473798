"""What the scheduler needs of the world outside it: a daemon connection per node
(`DaemonLink`, reached through a `Backend`) and the manager's registry (`Registry`, for
readiness and watchdogs); `StartError`, the one failure a start or stop reports."""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Protocol

from .daemon_resources import ResourceSample
from .daemon_wire import Exited, OutputLine, ProcessInfo, SpawnSpec, StateChanged

# The daemon's events as its client queues them; None, last, when the connection is gone.
DaemonEvent = OutputLine | Exited | StateChanged | ResourceSample


class DaemonLink(Protocol):
    """What the scheduler uses of a daemon connection (daemon_client.DaemonClient)."""

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


class StartError(Exception):
    """A process (or state) could not be brought up; the text says why."""
