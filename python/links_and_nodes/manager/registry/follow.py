"""A part of the manager that follows the registry: one task that wakes on every change of
the core's clients and ports (core.listeners) and brings something else in line with them,
such as the daemons' loggers (loggers/) or pull topics (network/pull.py).  Changes made while
it works wake it once more; close() stops it and unhooks it from the core."""

from __future__ import annotations

import asyncio
import contextlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .core import Core


class RegistryFollower:
    """Base of the followers: `_follow()` is the task; it waits on `_dirty`; `_lock`
    serializes its changes with those that commands make."""

    def __init__(self, core: Core) -> None:
        self.core = core
        self._dirty = asyncio.Event()
        self._lock = asyncio.Lock()
        self._task: asyncio.Task[None] | None = None

    def start(self) -> None:
        self.core.listeners.append(self._dirty.set)
        self._task = asyncio.get_running_loop().create_task(self._follow())

    async def _follow(self) -> None:
        raise NotImplementedError

    async def _stop_following(self) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
            self._task = None
        with contextlib.suppress(ValueError):
            self.core.listeners.remove(self._dirty.set)
