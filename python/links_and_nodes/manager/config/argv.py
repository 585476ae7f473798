"""Splitting a process's `command` into its argv, the one home of that rule: POSIX shell
words (shlex), no shell expansions.  The configuration splits every command not started in
a shell when it is loaded, so a bad quote is reported at its file:line:col."""

from __future__ import annotations

import shlex


class CommandSplitError(ValueError):
    """The command cannot be split; `offset` is where in it the trouble starts."""

    def __init__(self, message: str, offset: int) -> None:
        super().__init__(message)
        self.offset = offset


def split_command(command: str) -> list[str]:
    """The words of `command` as a POSIX shell splits them (quotes and backslashes, no
    expansions); CommandSplitError at an unclosed quote or a final lone backslash."""
    try:
        return shlex.split(command)
    except ValueError:
        raise _split_error(command) from None


def _split_error(command: str) -> CommandSplitError:
    """Where shlex gave up: the quote left open, or the backslash with nothing after it."""
    quote, opened, i = "", 0, 0
    while i < len(command):
        c = command[i]
        if quote == "'":
            if c == "'":
                quote = ""
        elif c == "\\":
            if i + 1 == len(command):
                return CommandSplitError("the command ends in a backslash that escapes nothing", i)
            i += 1
        elif quote == '"':
            if c == '"':
                quote = ""
        elif c in "'\"":
            quote, opened = c, i
        i += 1
    if quote:
        kind = "single" if quote == "'" else "double"
        return CommandSplitError(f"unbalanced {kind} quote in the command: it is never closed",
                                 opened)
    return CommandSplitError("the command cannot be split into words", 0)
