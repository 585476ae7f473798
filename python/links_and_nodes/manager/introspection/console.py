"""The introspection commands in the manager's console (docs/introspection.md).  The console
runs in the manager's asyncio loop, so each command runs in a worker thread, with a libln
client connected to the manager's own port and CONTROL commands handed to the loop.
`topic info`, `md show` and `service call` are awaited; `topic echo|hz|bw` print in the
background until they are done (-n, --duration) or the next command line comes, like
`output -f`."""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Callable
from typing import Any, Protocol

from ..frontends.control import Control, ControlError, loop_control
from .args import UsageError, parse
from .commands import FOLLOWING, CommandError, Context, run

class _Console(Protocol):
    control: Control

    def say(self, text: str) -> None: ...

    def hold_watch(self, stop: Callable[[], None] | None) -> None:
        """End the command printing in the background, if one does (calling the `stop` it
        holds), then hold `stop` of the next one (None: none) until the next command line."""
        ...


class Watch:
    """One command running in a worker thread; its output stops with stop()."""

    def __init__(self, console: _Console, loop: asyncio.AbstractEventLoop) -> None:
        self.console = console
        self.loop = loop
        self.lock = threading.Lock()
        self.stop_event = threading.Event()
        self.done = asyncio.Event()
        self._control = loop_control(console.control, loop, CommandError)
        address = getattr(console.control, "manager_address", None) or ""
        self.context = Context(self.control, address, self.say, self.stop_event,
                               client_prefix="ln_console")

    def say(self, text: str) -> None:
        with self.lock:
            if not self.stop_event.is_set():
                self.console.say(text)

    def control(self, op: str, **fields: Any) -> dict[str, Any]:
        return self._control(op, **fields)

    def stop(self) -> None:
        with self.lock:  # after this, nothing more of it is printed
            self.stop_event.set()

    def run(self, key: tuple[str, str], args: dict[str, Any]) -> None:
        try:
            run(self.context, key, args)
        except CommandError as exc:
            self.say(f"error: {exc}")
        except Exception as exc:  # a bug of ours: say it, keep the manager running
            self.say(f"error: internal error: {exc!r}")
        finally:
            self.loop.call_soon_threadsafe(self.done.set)


async def execute(console: _Console, words: list[str]) -> None:
    """Run `topic ...`, `md ...` or `service ...` (words with the group first)."""
    try:
        key, args = parse(words)
    except UsageError as exc:
        raise ControlError(str(exc)) from None
    console.hold_watch(None)
    watch = Watch(console, asyncio.get_running_loop())
    thread = threading.Thread(target=watch.run, args=(key, args), daemon=True,
                              name=f"console-{key[0]}-{key[1]}")
    if key in FOLLOWING:
        console.hold_watch(watch.stop)
        thread.start()
        return
    thread.start()
    await watch.done.wait()

