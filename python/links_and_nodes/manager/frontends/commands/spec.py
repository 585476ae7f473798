"""What a manager command is: its arguments (Arg), the command itself (Command: help, handler,
result, how each front end shows it) and a console/CLI word that stands for a family of
commands with its own words (Verb: `logger ...`, `topic ...`, `param ...`).  Leaf module:
imports nothing of ours."""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Any

TYPES = ("str", "int", "float", "bool", "json")


class _Same:
    def __repr__(self) -> str:
        return "SAME"


SAME: Any = _Same()  # Arg.text_default: the same default as in a JSON request


class ArgError(Exception):
    """An argument that is missing or has a bad value: the one text every front end shows,
    with `code` the LN_E* name a JSON answer carries ("" for none)."""

    def __init__(self, text: str, code: str = "") -> None:
        super().__init__(text)
        self.code = code


@dataclass(frozen=True)
class Arg:
    """One argument of a command.

    type: "str" | "int" | "float" | "bool" | "json" (any JSON value).
    required: a JSON request must carry it; otherwise `default` is used.
    nonempty (str), low/high (int, float; inclusive), finite (float), nullable (null is
    a value, meaning "none"): the generic checks; `error` replaces their text.
    check(value) -> value: a check of the feature's own (after the generic ones), raising
    ArgError (or the feature's error) with its text.
    positional: a word of its own in the console and the CLI, else an option `flag`
    ("--name" unless given; a bool option takes no value).  text_default: the default
    there (SAME: `default`); console_required: the console insists on the word.
    where: "" (every front end), "console" or "cli": an option of one front end only,
    never sent to the manager (`output -f`, `start --wait`)."""

    name: str
    type: str
    help: str
    required: bool = False
    default: Any = None
    choices: tuple[Any, ...] = ()
    positional: bool = False
    flag: str = ""
    nonempty: bool = False
    low: float | None = None
    high: float | None = None
    finite: bool = False
    nullable: bool = False
    error: str = ""
    check: Callable[[Any], Any] | None = None
    text_default: Any = SAME
    console_required: bool = False
    where: str = ""
    metavar: str = ""

    def __post_init__(self) -> None:
        if self.type not in TYPES:
            raise ValueError(f"argument {self.name!r}: type {self.type!r} is not one of "
                             f"{', '.join(TYPES)}")

    @property
    def option(self) -> str:
        """How the console and the CLI spell it when it is not positional."""
        return self.flag or "--" + self.name.replace("_", "-")

    @property
    def word(self) -> str:
        """Its placeholder in a usage line."""
        return self.metavar or self.name.upper()


Handler = Callable[..., Awaitable[dict[str, Any]]]
Lines = Callable[[dict[str, Any], dict[str, Any]], list[str]]


@dataclass(frozen=True)
class Command:
    """One command of the manager, answered by Control.handle({"op": name, ...}).

    handler(control, args) -> result dict (args: every Arg with its value or default);
    with session=True handler(control, args, session): a command of a live connection
    (the web UI's subscriptions), refused where there is none.
    result: what the answer carries (for describe() and the docs).
    changes_state: it changes something (a process, a logger, the manager) rather than
    only looking; the web UI asks for its CSRF token.
    code: the LN_E* name an argument error carries in the JSON answer.
    slow: it may take as long as it takes (a client waits without a time limit).
    console / cli: the word in the console / the `ln_manager` subcommand ("" for none;
    True: the name, with "-" for "_" in the CLI).  aliases: more console words.
    console_format(result, args) / cli_format: the answer as lines (cli_format: the
    console's unless given); console_run(console, args) / cli_run(mgr, args): the whole
    command where a front end does more than ask and print (return True from console_run
    to end the console).  json_view(result): what `--json` prints (default: the result
    without "ok").
    phrase: the words that name it in the console and the CLI when it is one of a family of
    commands (`logger NAME add`, `logger`): the family's word, then literal words and, in
    capitals, the values of its first positional arguments (commands/phrases.py).
    script: the scripting API method (True: the name; "" for none); script_result(result)
    -> what it returns (default the result); script_wait: the argument that says how
    long the answer may take."""

    name: str
    help: str
    group: str
    handler: Handler
    args: tuple[Arg, ...] = ()
    result: str = "{}"
    changes_state: bool = False
    code: str = ""
    slow: bool = False
    session: bool = False
    console: bool | str = True
    aliases: tuple[str, ...] = ()
    console_format: Lines | None = None
    console_run: Callable[..., Awaitable[bool | None]] | None = None
    cli: bool | str = True
    cli_help: str = ""
    cli_format: Lines | None = None
    cli_run: Callable[..., list[str]] | None = None
    json_view: Callable[[dict[str, Any]], Any] | None = None
    script: bool | str = True
    script_result: Callable[[dict[str, Any]], Any] | None = None
    script_wait: str = ""
    script_doc: str = ""
    phrase: str = ""

    @property
    def console_word(self) -> str:
        if self.phrase:
            return self.phrase if self.console else ""
        return self.name if self.console is True else (self.console or "")

    @property
    def cli_word(self) -> str:
        if self.phrase:
            return self.phrase if self.cli else ""
        return self.name.replace("_", "-") if self.cli is True else (self.cli or "")

    @property
    def family(self) -> str:
        """The first word of its phrase ("" for a command of its own)."""
        return self.phrase.split()[0] if self.phrase else ""

    @property
    def placed(self) -> tuple[str, ...]:
        """The positional arguments whose values stand inside its phrase."""
        return tuple(w for w in self.phrase.split()[1:] if w.isupper())

    @property
    def script_name(self) -> str:
        return self.name if self.script is True else (self.script or "")

    def arg(self, name: str) -> Arg:
        for a in self.args:
            if a.name == name:
                return a
        raise KeyError(name)

    def usage(self, where: str = "console") -> str:
        """`start NAME|GROUP|all`, `output NAME [-n N] [-f]`: the words it takes."""
        word = self.console_word if where == "console" else self.cli_word
        parts = [word]
        for a in self.args:
            if a.where not in ("", where) or (a.positional and a.word in self.placed):
                continue
            if a.positional:
                needed = a.required or (where == "console" and a.console_required)
                parts.append(a.word if needed else f"[{a.word}]")
            elif a.type == "bool":
                parts.append(f"[{a.option}]")
            else:
                parts.append(f"[{a.option} {a.metavar or a.name[:1].upper()}]")
        return " ".join(parts)


@dataclass(frozen=True)
class Verb:
    """A console word and `ln_manager` subcommand that stands for a family of commands with
    words of their own (`logger NAME add TOPIC`, `topic echo NAME`, `param set ...`).

    usage: the help lines (usage, then its text indented), console(console, words) runs
    it in the console (words after the verb), cli(argv) -> exit status runs `ln_manager
    VERB ...` (argv with the verb first); words: what may follow it (completion)."""

    name: str
    help: str
    group: str
    usage: tuple[str, ...]
    console: Callable[[Any, list[str]], Awaitable[None]] | None
    cli: Callable[[list[str]], int] | None
    words: tuple[str, ...] = ()
