"""The manager's console: one command per line on stdin, from a terminal or a pipe, answered
on stdout.  Its commands, their words, `help` and the completion of a line come from the
command table (commands/); every command goes through control.Control, like remote ones.
On a terminal, lines are read with readline and Tab completes from the table."""

from __future__ import annotations

import asyncio
import shlex
import sys
import threading
from collections.abc import Callable
from typing import Any, TextIO

from ...tools.commands import ArgError, ControlError, console_entry, parse_words, to_request
from . import console_run
from .commands import phrases
from .commands.help import complete, help_command, help_text
from .commands.views import format_network, format_status, json_lines, table
from .control import Control

__all__ = ["Console", "complete", "format_network", "format_status", "stdin_reader", "table"]


class Console:
    def __init__(self, control: Control, out: TextIO | None = None) -> None:
        self.control = control
        self.out = out or sys.stdout
        self._follow: Callable[[str, Any], None] | None = None
        # ends the printing of a streaming command in the background (console_run.py)
        self._stop_watch: Callable[[], None] | None = None

    def say(self, text: str) -> None:
        self.out.write(text + "\n")
        self.out.flush()

    async def run(self, stream: asyncio.StreamReader) -> None:
        """Read and run commands until `quit`/`detach` or the end of input (which ends only
        the console, not the manager)."""
        try:
            while True:
                raw = await stream.readline()
                if not raw:
                    return
                line = raw.decode(errors="replace").strip()
                self._unfollow()
                if not line or line.startswith("#"):
                    continue
                if await self.execute(line):
                    return
        finally:
            self._unfollow()

    async def execute(self, line: str) -> bool:
        """Run one command line; True when the console should end (quit, detach)."""
        try:
            words = shlex.split(line)
        except ValueError as exc:
            self.say(f"error: {exc}")
            return False
        if not words:
            return False
        cmd, args = words[0], words[1:]
        try:
            return await self._dispatch(cmd, args)
        except (ControlError, ArgError) as exc:
            self.say(f"error: {exc}")
        return False

    async def _dispatch(self, word: str, words: list[str]) -> bool:
        """Run a command of the table (commands/): its words checked by the table, then
        Control.handle, then its console view."""
        if word in ("help", "?"):
            self.say(help_command(" ".join(words)) if words else help_text())
            return False
        entry: Any = None
        if word in phrases.families():  # `logger NAME add ...`: a command of a family
            entry, words = phrases.match([word, *words])
        else:
            entry = console_entry(word)
        if entry is None:
            raise ControlError(f"unknown command {word!r} (try help)")
        args = parse_words(entry, words)
        if entry.run is not None:
            await console_run.execute(self, entry, args)
            return False
        if entry.console_run is not None:
            return bool(await entry.console_run(self, args))
        result = await self.control.handle(to_request(entry, args))
        view = entry.console_format or json_lines
        for text in view(result, args):
            self.say(text)
        return False

    def follow_output(self, name: str) -> None:
        """Print every new output line of process `name` until the next command line."""
        if self.control.scheduler is None:
            return

        def follow_line(proc: str, line: Any) -> None:
            if proc == name:
                self.say(f"{name}: {line.text}")
        self._follow = follow_line
        self.control.scheduler.output_listeners.append(follow_line)

    def hold_watch(self, stop: Callable[[], None] | None) -> None:
        """End a streaming command printing in the background, if one does; hold `stop` of
        the next one (None: none).  Its thread ends within a read slice, closing its client
        on its own: never waited for here, since its goodbye to the manager needs this
        loop."""
        if self._stop_watch is not None:
            self._stop_watch()
        self._stop_watch = stop

    def _unfollow(self) -> None:
        self.hold_watch(None)  # a streaming command (topic echo, ...)
        if self._follow is not None and self.control.scheduler is not None:
            self.control.scheduler.output_listeners.remove(self._follow)
        self._follow = None


async def stdin_reader() -> asyncio.StreamReader:
    """An asyncio stream over this process's stdin (a terminal, pipe or file)."""
    loop = asyncio.get_running_loop()
    reader = asyncio.StreamReader()
    if sys.stdin.isatty() and _readline_pump(loop, reader):
        return reader
    try:
        await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(reader), sys.stdin)
    except ValueError:  # a regular file: no pipe transport, read it in a thread
        def pump() -> None:
            for raw in sys.stdin.buffer:
                loop.call_soon_threadsafe(reader.feed_data, raw)
            loop.call_soon_threadsafe(reader.feed_eof)
        threading.Thread(target=pump, name="console-stdin", daemon=True).start()
    return reader


def _readline_pump(loop: asyncio.AbstractEventLoop, reader: asyncio.StreamReader) -> bool:
    """On a terminal: read lines with readline (history, editing, Tab completing from the
    command table) in a thread; False where readline is missing."""
    try:
        import readline
    except ImportError:
        return False
    matches: list[str] = []

    def completer(text: str, state: int) -> str | None:
        if state == 0:
            line = readline.get_line_buffer()[:readline.get_endidx()]
            matches[:] = complete(line)
        return matches[state] if state < len(matches) else None

    try:  # readline changes the terminal while it waits: give it back as it was at exit
        import atexit
        import termios

        saved = termios.tcgetattr(sys.stdin.fileno())
        atexit.register(termios.tcsetattr, sys.stdin.fileno(), termios.TCSADRAIN, saved)
    except (ImportError, OSError):
        pass
    readline.set_completer(completer)
    readline.set_completer_delims(" \t")
    readline.parse_and_bind("tab: complete")

    def pump() -> None:
        while True:
            try:
                line = input()
            except EOFError:
                break
            except KeyboardInterrupt:
                continue
            loop.call_soon_threadsafe(reader.feed_data, (line + "\n").encode())
        loop.call_soon_threadsafe(reader.feed_eof)

    threading.Thread(target=pump, name="console-readline", daemon=True).start()
    return True
