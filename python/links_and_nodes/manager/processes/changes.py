"""Change notification for the scheduler: tasks wait until a condition on the processes'
states holds, and every state change wakes all of them at once to look again.

Unlike asyncio.Condition there is no lock to hand from waiter to waiter: with many
processes waiting for their dependencies, one change wakes them all in the same turn of
the event loop instead of one per turn, which kept a large start tree's processes waiting
milliseconds per level.  Waiters run in the event loop only, so looking at the states
needs no lock."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable


class Changes:
    def __init__(self) -> None:
        self._waiters: list[asyncio.Future[None]] = []

    def notify(self) -> None:
        """Wake every waiter: each looks at its condition again."""
        waiters, self._waiters = self._waiters, []
        for fut in waiters:
            if not fut.done():
                fut.set_result(None)

    async def wait_for(self, predicate: Callable[[], bool]) -> None:
        """Until predicate() is true (looked at now and after every change); whatever it
        raises ends the wait with that exception."""
        loop = asyncio.get_running_loop()
        while not predicate():
            fut: asyncio.Future[None] = loop.create_future()
            self._waiters.append(fut)
            try:
                await fut
            finally:
                if fut.cancelled():  # the wait was (a timeout): not kept until a notify
                    with contextlib.suppress(ValueError):  # unless a notify took it
                        self._waiters.remove(fut)
