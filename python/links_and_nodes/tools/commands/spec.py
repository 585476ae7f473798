"""What a manager command is: its arguments (Arg), the command itself (Command: help, handler
or a run in the client, result, how each front end shows it) and the first word of a family
of commands named by phrases (Verb: `logger ...`, `topic ...`, `param ...`).  Leaf module:
imports nothing of ours."""

from __future__ import annotations

from collections.abc import Awaitable, Callable, Iterator
from dataclasses import dataclass
from typing import Any

TYPES = ("str", "int", "float", "bool", "json")
WHERE = ("", "console", "cli", "text")  # Arg.where: every front end, one, or both of them
REST = ("", "join", "words")  # Arg.rest


class _Same:
    def __repr__(self) -> str:
        return "SAME"


SAME: Any = _Same()  # Arg.text_default: the same default as in a JSON request


class ArgError(ValueError):
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
    a value, meaning "none"): the generic checks; `error` replaces their text, with
    `{value!r}` in it standing for the value as it was given (the word as typed).
    check(value) -> value: a check of the feature's own (after the generic ones), raising
    ArgError (or the feature's error) with its text.
    positional: a word of its own in the console and the CLI, else an option `flag`
    ("--name" unless given; a bool option takes no value; `short`: one more spelling).
    rest: the last positional takes every word that is left, "join"ed by spaces (a request
    text) or as the list of "words" (`PARAM VALUE ...`).  text_default: the default
    there (SAME: `default`); console_required: the console insists on the word.
    where: "" (every front end), "console", "cli" or "text" (both): an option of those
    front ends only, never sent to the manager (`output -f`, `start --wait`, `--json`)."""

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
    short: str = ""
    rest: str = ""

    def __post_init__(self) -> None:
        if self.type not in TYPES:
            raise ValueError(f"argument {self.name!r}: type {self.type!r} is not one of "
                             f"{', '.join(TYPES)}")
        if self.where not in WHERE or self.rest not in REST:
            raise ValueError(f"argument {self.name!r}: where {self.where!r} or rest "
                             f"{self.rest!r} unknown")

    def at(self, where: str) -> bool:
        """Whether front end `where` ("" for a JSON request, "console", "cli") has it."""
        return self.where in ("", where) or (self.where == "text" and where in ("console",
                                                                               "cli"))

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
# Command.run: (local.Local, args) -> the answer, or with streams=True its rows as they come
Run = Callable[[Any, dict[str, Any]], dict[str, Any] | Iterator[dict[str, Any]]]


@dataclass(frozen=True)
class Command:
    """One command of the manager, answered by Control.handle({"op": name, ...}).

    handler(control, args) -> result dict (args: every Arg with its value or default);
    with session=True handler(control, args, session): a command of a live connection
    (the web UI's subscriptions), refused where there is none.
    run(local, args), instead of a handler: the command runs in a client of the manager,
    where its user is (the process of `ln_manager COMMAND`, the scripting client, a worker
    thread of the console or of the manager for a JSON request), with a local.Local that
    asks the manager and connects libln clients; it returns the answer, or with
    streams=True yields rows as they come (`topic echo`: a sample each) until its count,
    its time or local.stop.  The console and the CLI print each row as it comes (the
    console's view of it), the scripting API collects them (script_result gets the list),
    a JSON request is answered {"rows": [...]}.  failed(result) -> "" or the text of a
    failure the console and the CLI report after the answer's lines (exit status 1).
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
    long the answer may take; script_args: a function whose signature is the method's
    and which returns the arguments (where the Python spelling differs from the words:
    `topic_echo(name, n=1, field=None, timeout=10.0)`).
    missing_usage: a missing positional word is answered with the usage line, not the
    argument's text."""

    name: str
    help: str
    group: str
    handler: Handler | None
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
    script_result: Callable[[Any], Any] | None = None
    script_wait: str = ""
    script_doc: str = ""
    script_args: Callable[..., dict[str, Any]] | None = None
    phrase: str = ""
    run: Run | None = None
    streams: bool = False
    failed: Callable[[dict[str, Any]], str] | None = None
    missing_usage: bool = False

    def __post_init__(self) -> None:
        if (self.handler is None) == (self.run is None):
            raise ValueError(f"command {self.name!r}: give a handler or a run, not both")

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
            if not a.at(where) or (a.positional and a.word in self.placed):
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
    """The first word of a family of commands named by phrases (`logger NAME add TOPIC`,
    `topic echo NAME`, `param set ...`): its help for `help WORD` and `ln_manager WORD
    --help`.  choose: the family's word for its commands ("command": a line that names
    none of them is answered `topic needs a command (one of: bw, echo, ...)` or `unknown
    topic command 'x' (one of: ...)`; "": with the family's usage)."""

    name: str
    help: str
    group: str
    choose: str = ""
