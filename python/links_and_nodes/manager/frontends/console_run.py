"""The commands that run in a client (Command.run: `topic echo`, `param set`, ...) in the
manager's console.  The console runs in the manager's asyncio loop and these commands block
(libln clients connected to the manager's own port), so each runs in a worker thread, its
CONTROL requests handed to the loop.  A command that answers once is awaited; one that
streams prints in the background until it ends or the next command line comes, like
`output -f`."""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Callable
from typing import Any, Protocol

from ...tools.commands import ArgError, Command, ControlError, Local
from ...tools.commands.from_thread import loop_control
from ...tools.commands.local import rows
from .commands.views import json_lines


class _Console(Protocol):
    control: Any  # the manager's Control (control.py): handle(), manager_address

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
        self.done = asyncio.Event()
        address = getattr(console.control, "manager_address", None) or ""
        self.local = Local(loop_control(console.control, loop, ControlError), address,
                           "ln_console")

    def say(self, text: str) -> None:
        with self.lock:
            if not self.local.stop.is_set():
                self.console.say(text)

    def stop(self) -> None:
        with self.lock:  # after this, nothing more of it is printed
            self.local.stop.set()

    def run(self, cmd: Command, args: dict[str, Any]) -> None:
        view = cmd.console_format or json_lines
        try:
            for row in rows(cmd, self.local, args):
                for line in view(row, args):
                    self.say(line)
                failure = cmd.failed(row) if cmd.failed is not None else ""
                if failure:
                    self.say(f"error: {failure}")
        except (ArgError, ControlError) as exc:
            self.say(f"error: {exc}")
        except Exception as exc:  # a bug of ours: say it, keep the manager running
            self.say(f"error: internal error: {exc!r}")
        finally:
            self.local.close()  # in this thread: a libln client's goodbye needs the loop
            self.loop.call_soon_threadsafe(self.done.set)


async def execute(console: _Console, cmd: Command, args: dict[str, Any]) -> None:
    """Run `cmd` (Command.run) with checked arguments: awaited, or in the background until
    the next command line when it streams."""
    console.hold_watch(None)
    watch = Watch(console, asyncio.get_running_loop())
    thread = threading.Thread(target=watch.run, args=(cmd, args), daemon=True,
                              name=f"console-{cmd.name}")
    if cmd.streams:
        console.hold_watch(watch.stop)
        thread.start()
        return
    thread.start()
    await watch.done.wait()
