"""The console's `help` (every command, or one with its arguments) and its completion of a
line, both read from the command table."""

from __future__ import annotations

import textwrap

from ....tools.commands.spec import SAME, Command
from ....tools.commands.table import commands, console_entry, verb
from . import phrases

WIDTH = 25  # column of the help texts
LINE = 92  # their right margin


def _entry(usage: str, text: str) -> list[str]:
    texts = textwrap.wrap(text, LINE - WIDTH - 1) or [""]
    lines = [f"  {usage:<{WIDTH - 1}}{texts[0]}"] if len(usage) < WIDTH - 1 else \
        [f"  {usage}", f"  {'':<{WIDTH - 1}}{texts[0]}"]
    return lines + [f"  {'':<{WIDTH - 1}}{more}" for more in texts[1:]]


def help_text() -> str:
    """`help`: every console command with its words and what it does."""
    lines = ["commands:"]
    for cmd in commands():
        if cmd.console_word:
            lines += _entry(cmd.usage("console"), cmd.help)
    lines += _entry("help [COMMAND]", "this text, or one command with its arguments")
    return "\n".join(lines)


def _arg_line(cmd: Command, name: str) -> str:
    arg = cmd.arg(name)
    spell = arg.word if arg.positional else ", ".join(filter(None, (arg.option, arg.short)))
    default = arg.default if arg.text_default is SAME else arg.text_default
    notes = [arg.type]
    if arg.choices:
        notes.append("one of " + ", ".join(str(c) for c in arg.choices))
    if default not in (None, "", False) and not arg.required:
        notes.append(f"default {default}")
    return f"  {spell:<{WIDTH - 1}}{arg.help} ({'; '.join(notes)})"


def help_command(word: str) -> str:
    """`help COMMAND`: its usage, text and arguments (`help logger`: the family's usage,
    `help logger add`: that command of the family)."""
    words = word.split() or [""]
    if words[0] in phrases.families():
        named = [c for c in phrases.family(words[0])
                 if len(words) > 1 and (c.phrase == word or phrases.said(c) == words)]
        if len(named) != 1:
            about = verb(words[0])
            return phrases.usage(words[0]) + (f"\n\n{about.help}" if about else "")
        entry: Command | None = named[0]
    else:
        word = words[0]
        entry = console_entry(word)
    if entry is None:
        return f"unknown command {word!r} (try help)"
    lines = [f"usage: {entry.usage('console')}", f"  {entry.help}"]
    lines += [_arg_line(entry, a.name) for a in entry.args if a.at("console")]
    return "\n".join(lines)


def complete(line: str) -> list[str]:
    """The words that may complete the last word of `line` (a console line being typed)."""
    words = line.split()
    if line.endswith(" ") or not words:
        words.append("")
    *before, last = words
    if not before:
        names = [c.console_word for c in commands() if c.console_word]
        names += [a for c in commands() if c.console_word for a in c.aliases] + ["help"]
        names = [n.split()[0] for n in names]
        return sorted(n for n in set(names) if n.startswith(last))
    if before[0] == "help" and len(before) == 1:
        return complete(last)
    if before[0] in phrases.families():
        return sorted(w for w in set(phrases.following(before)) if w.startswith(last))
    entry = console_entry(before[0])
    if isinstance(entry, Command):
        options = [a.option for a in entry.args if not a.positional and a.at("console")]
        choices = [str(c) for a in entry.args if a.positional for c in a.choices]
        return sorted(w for w in options + choices if w.startswith(last))
    return []
