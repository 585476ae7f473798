"""`%( )` evaluation of `.lnc` values: defines, builtin defines and builtin functions.

Calls nest (`%(env %(var))`): inner calls are expanded first, then the call's text is
either a name (template argument, builtin or define) or `FUNCTION ARGS`.  The
conditionals (`ifdef`, `ifndef`, `ifeq`, `ifexists`) evaluate only the branch they
take; the other is checked for unknown names, which are warnings there.  Results are
not expanded again, so a value can never expand forever.
"""

from __future__ import annotations

import os
import re
import sys
import zlib
from collections.abc import Mapping

from .errors import LineError, Problem, did_you_mean, shift
from .model import Location
from .shell import SHELL_TIMEOUT, CommandError, run_command
from .text import split_args, unescape, unquote

MAX_DEPTH = 16  # nesting of %( ) calls
CONDITIONALS = ("ifdef", "ifndef", "ifeq", "ifexists")  # evaluate one branch only
FUNCTIONS = ("env", "dirname", "basename", "subst", "get_port_from_string", "shell",
             *CONDITIONALS)
# conditional -> (fewest, most arguments, usage), and the arguments that are its branches
_CONDITIONAL_ARITY = {
    "ifdef": (2, 3, '"NAME", "THEN" or "NAME", "THEN", "ELSE"'),
    "ifndef": (2, 2, '"NAME", "DEFAULT"'),
    "ifeq": (3, 4, '"A", "B", "THEN" or "A", "B", "THEN", "ELSE"'),
    "ifexists": (2, 3, '"PATH", "THEN" or "PATH", "THEN", "ELSE"')}
_BRANCHES = {"ifdef": (1, 2), "ifndef": (1,), "ifeq": (2, 3), "ifexists": (1, 2)}
_CONDITIONAL_RE = re.compile(r"\s*(" + "|".join(CONDITIONALS) + r")\s")
CONTEXT_BUILTINS = ("CURDIR", "CURRENT", "_PROCESS", "_FULL_PROCESS")
GLOBAL_BUILTINS = ("instance_name", "hostname", "manager", "LN_PYTHON", "LN_PYTHONPATH")
BUILTINS = frozenset(CONTEXT_BUILTINS + GLOBAL_BUILTINS + FUNCTIONS)
PORT_BASE = 20000
PORT_RANGE = 12000


def port_from_string(text: str) -> int:
    """A TCP port that depends only on `text`: 20000 + CRC-32(UTF-8 of text) mod 12000.

    The range 20000..31999 lies above the usual service ports and below Linux's default
    ephemeral range (32768..60999), so the port is not handed out to outgoing
    connections.  Different strings can map to the same port."""
    return PORT_BASE + zlib.crc32(text.encode("utf-8", "surrogateescape")) % PORT_RANGE


class Evaluator:
    """Holds the defines as they are at the current line and expands text."""

    def __init__(self, env: Mapping[str, str], fixed: Mapping[str, str], hostname: str,
                 manager: str | None, shell_timeout: float = SHELL_TIMEOUT) -> None:
        self.env = env
        self.defines: dict[str, str] = dict(fixed)
        self.fixed = frozenset(fixed)  # given by the caller: the files cannot change them
        self.hostname = hostname
        self.manager_override = manager
        self.shell_timeout = shell_timeout
        self.instance_name: str | None = None
        self.manager: str | None = None  # as written in the instance section
        self.process: tuple[str, str] | None = None  # (name, full name) of the last process
        # Names whose defining line had a problem: a line using them is skipped quietly.
        self.broken: set[str] = set()
        self.warnings: list[Problem] = []
        self._poisoned = False
        self._dry = 0  # > 0 while checking a branch that is not taken
        self._level = 0  # conditionals being evaluated around the current text

    # ------------------------------------------------------------------ names

    def lookup(self, name: str, file: str, args: Mapping[str, str] | None) -> str | None:
        """The value of a name at this point, or None when it has none."""
        if args is not None and name in args:
            return args[name]
        if name == "CURDIR":
            return os.path.dirname(os.path.abspath(file))
        if name == "CURRENT":
            return os.path.abspath(file)
        if name in ("_PROCESS", "_FULL_PROCESS"):
            return None if self.process is None else self.process[name == "_FULL_PROCESS"]
        if name in self.defines:
            return self.defines[name]
        if name == "instance_name":
            return self.instance_name
        if name == "hostname":
            return self.hostname
        if name == "manager":
            address = self.manager_override or self.manager
            if address is not None and address.startswith(":"):
                return self.hostname + address
            return address
        if name == "LN_PYTHON":
            return sys.executable
        if name == "LN_PYTHONPATH":
            here = os.path.dirname(os.path.abspath(__file__))
            return os.path.normpath(os.path.join(here, "..", "..", ".."))
        return None

    def is_defined(self, name: str, args: Mapping[str, str] | None) -> bool:
        """What `ifdef` tests: a define or a template argument (builtins do not count)."""
        return name in self.defines or (args is not None and name in args)

    def known_names(self, args: Mapping[str, str] | None) -> list[str]:
        return [*(args or {}), *self.defines, *CONTEXT_BUILTINS, *GLOBAL_BUILTINS]

    # ------------------------------------------------------------------ expansion

    def expand(self, text: str, loc: Location, file: str,
               args: Mapping[str, str] | None = None) -> str:
        """`text` with every `%( )` call replaced; `loc` is where `text` starts.  Raises
        LineError with every problem of the text."""
        if "%(" not in text:
            return text
        problems: list[Problem] = []
        self._poisoned = False
        self._dry = self._level = 0
        out, _ = self._scan(text, 0, 0, loc, file, args, problems)
        if problems or self._poisoned:
            # A name whose own line failed: that problem is reported already, so this
            # line is skipped without another.
            raise LineError(problems)
        return out

    def _scan(self, text: str, i: int, depth: int, loc: Location, file: str,
              args: Mapping[str, str] | None, problems: list[Problem]) -> tuple[str, int]:
        """Expand from `i`.  Inside a call (depth > 0) stop after its closing `)`.
        Returns the text and the index after it, -1 when the call is not closed.
        Offsets in `text` are columns from `loc`."""
        out: list[str] = []
        nesting = _Nesting()
        while i < len(text):
            if text.startswith("%(", i):
                if depth + self._level >= MAX_DEPTH:
                    raise LineError([*problems, Problem(shift(loc, i),
                                                        f"'%(' nested more than {MAX_DEPTH} deep")])
                cond = _CONDITIONAL_RE.match(text, i + 2)
                if cond is not None:
                    end = call_end(text, i + 2)
                    if end >= 0:
                        if not self._poisoned:
                            out.append(self._conditional(cond.group(1), text, cond.end(),
                                                         end - 1, depth + 1, i, loc, file,
                                                         args, problems))
                        i = end
                        continue
                inner, end = self._scan(text, i + 2, depth + 1, loc, file, args, problems)
                if end < 0:
                    if depth == 0:
                        problems.append(Problem(shift(loc, i), "unterminated '%(' (missing ')')"))
                    return "".join(out), -1
                # A call around a name whose line failed is not evaluated: no second problem.
                if not self._poisoned:
                    out.append(self._call(inner, shift(loc, i), file, args, problems))
                i = end
                continue
            if not depth:
                out.append(text[i])
                i += 1
                continue
            nxt, closing = nesting.feed(text, i)
            if closing:
                return "".join(out), nxt
            out.append(text[i:nxt])
            i = nxt
        return "".join(out), -1 if depth else i

    def _conditional(self, name: str, text: str, start: int, stop: int, depth: int,
                     at: int, loc: Location, file: str, args: Mapping[str, str] | None,
                     problems: list[Problem]) -> str:
        """`%(NAME ARGS)` for a conditional whose arguments are `text[start:stop]`
        (unexpanded); `at` is the index of its `%(`."""
        call_loc = shift(loc, at)
        spans = arg_spans(text, start, stop)

        def arg(k: int) -> str:
            first, last, quoted = spans[k]
            self._level += depth
            try:
                value, _ = self._scan(text[:last], first, 0, loc, file, args, problems)
            finally:
                self._level -= depth
            return unescape(value) if quoted and "%(" not in text[first:last] else value

        def skip(*ks: int) -> None:
            """Check branches not taken: unknown names there are warnings."""
            self._dry += 1
            try:
                for k in ks:
                    if k < len(spans):
                        arg(k)
            finally:
                self._dry -= 1

        least, most, usage = _CONDITIONAL_ARITY[name]
        if not least <= len(spans) <= most:
            problems.append(Problem(call_loc, f"'{name}' takes {usage}, got {len(spans)} "
                                              f"argument{'s' if len(spans) != 1 else ''}"))
            return ""
        if self._dry:
            skip(*range(len(spans)))
            return ""
        if name == "ifeq":
            taken = 2 if arg(0) == arg(1) else 3
        elif name == "ifexists":
            path = arg(0)
            base = os.path.dirname(os.path.abspath(file))
            taken = 1 if path and os.path.exists(os.path.join(base, path)) else 2
        else:
            define = arg(0).strip()
            if name == "ifndef":
                if self.is_defined(define, args):
                    skip(1)
                    value = self.lookup(define, file, args)
                    return "" if value is None else value
                return arg(1)
            taken = 1 if self.is_defined(define, args) else 2
        skip(*(k for k in _BRANCHES[name] if k != taken))
        return arg(taken) if taken < len(spans) else ""

    def _call(self, inner: str, loc: Location, file: str, args: Mapping[str, str] | None,
              problems: list[Problem]) -> str:
        m = re.match(r"\s*(\S+)(?:\s+(.*?))?\s*\Z", inner, re.S)
        if m is None:
            problems.append(Problem(loc, "empty '%()'"))
            return ""
        name, rest = m.group(1), m.group(2)
        if rest is None and name not in FUNCTIONS:
            value = self.lookup(name, file, args)
            if value is None and name in self.broken:
                self._poisoned = True
                return ""
            if value is None:
                message = self._undefined(name, args)
                if self._dry:
                    self.warnings.append(Problem(loc, f"{message} (in a branch that is not "
                                                      "taken)"))
                else:
                    problems.append(Problem(loc, message))
                return ""
            return value
        if name not in FUNCTIONS:
            hint = did_you_mean(name, FUNCTIONS)
            problems.append(Problem(loc, f"unknown function '{name}' in '%()'{hint}"))
            return ""
        if self._dry:  # a branch not taken: nothing runs
            return ""
        try:
            if name == "shell":
                return self._shell(rest or "", file)
            return self._function(name, split_args(rest or ""))
        except ValueError as exc:
            problems.append(Problem(loc, str(exc)))
            return ""

    def _undefined(self, name: str, args: Mapping[str, str] | None) -> str:
        if name in ("_PROCESS", "_FULL_PROCESS"):
            return f"'{name}' is only defined in and after a process section"
        if name == "instance_name":
            return "'instance_name' is used before the instance section sets 'name'"
        if name == "manager":
            return "'manager' is used before the instance section sets 'manager'"
        hint = did_you_mean(name, self.known_names(args))
        return f"unknown name '{name}' in '%()'{hint}"

    def run(self, command: str, file: str) -> str:
        """stdout of a shell command run in the directory of `file`; ValueError when it
        fails or times out."""
        try:
            return run_command(command, os.path.dirname(os.path.abspath(file)), self.env,
                               self.shell_timeout)
        except CommandError as exc:
            raise ValueError(str(exc)) from None

    def _shell(self, rest: str, file: str) -> str:
        """`%(shell "COMMAND")` or `%(shell COMMAND)`: its stdout without the trailing
        newlines (as `$( )` in a shell)."""
        command, _ = unquote(rest.strip())
        return self.run(command, file).rstrip("\n")

    def _function(self, name: str, fargs: list[str]) -> str:
        def need(lo: int, hi: int, usage: str) -> None:
            if not lo <= len(fargs) <= hi:
                raise ValueError(f"'{name}' takes {usage}, got {len(fargs)} "
                                 f"argument{'s' if len(fargs) != 1 else ''}")

        if name == "env":
            need(1, 2, "NAME or NAME, DEFAULT")
            if fargs[0] in self.env:
                return self.env[fargs[0]]
            if len(fargs) == 2:
                return fargs[1]
            raise ValueError(f"environment variable '{fargs[0]}' is not set "
                             f"(a default is given as '%(env {fargs[0]}, DEFAULT)')")
        if name in ("dirname", "basename"):
            need(1, 1, "one argument")
            return getattr(os.path, name)(fargs[0])
        if name == "subst":
            need(3, 3, '3 arguments: "FROM", "TO", "STRING"')
            if not fargs[0]:
                raise ValueError("'subst' cannot replace an empty string")
            return fargs[2].replace(fargs[0], fargs[1])
        if name in CONDITIONALS:  # written without arguments: `%(ifdef)`
            raise ValueError(f"'{name}' needs arguments")
        need(1, 1, "one argument")
        return str(port_from_string(fargs[0]))


class _Nesting:
    """Where a `%( )` call's text stands: inside double quotes (with `\\` escapes) and how
    many unquoted `(` are open, which decides the `)` that closes the call."""

    def __init__(self) -> None:
        self.quoted = False
        self.parens = 0

    @property
    def top(self) -> bool:
        return not self.quoted and self.parens == 0

    def feed(self, text: str, i: int) -> tuple[int, bool]:
        """Take the character at `i` (two for an escape in quotes): the index after it and
        whether it is the `)` that closes the call."""
        c = text[i]
        if self.quoted and c == "\\" and i + 1 < len(text):
            return i + 2, False
        if c == '"':
            self.quoted = not self.quoted
        elif not self.quoted and c == "(":
            self.parens += 1
        elif not self.quoted and c == ")":
            if self.parens == 0:
                return i + 1, True
            self.parens -= 1
        return i + 1, False


def call_end(text: str, i: int) -> int:
    """Index after the `)` that closes the call whose text starts at `i` (after its `%(`),
    or -1; the same rules as Evaluator._scan (quotes, nested calls, balanced parens)."""
    nesting = _Nesting()
    while i < len(text):
        if text.startswith("%(", i):
            i = call_end(text, i + 2)
            if i < 0:
                return -1
            continue
        i, closing = nesting.feed(text, i)
        if closing:
            return i
    return -1


def arg_spans(text: str, start: int, stop: int) -> list[tuple[int, int, bool]]:
    """The comma-separated arguments in `text[start:stop]`, unexpanded: (first, last,
    quoted) of each, without surrounding blanks and, when quoted, inside the quotes.
    Commas inside quotes or nested calls do not separate; no arguments gives []."""
    if not text[start:stop].strip():
        return []
    spans = []
    nesting = _Nesting()
    bounded = text[:stop]
    first = i = start
    while True:
        if i >= stop or (text[i] == "," and nesting.top):
            spans.append(_trim(text, first, min(i, stop)))
            if i >= stop:
                return spans
            first = i = i + 1
            continue
        if text.startswith("%(", i):
            end = call_end(text, i + 2)
            i = stop if end < 0 or end > stop else end
            continue
        i, _ = nesting.feed(bounded, i)  # a stray `)` closes nothing here


def _trim(text: str, first: int, last: int) -> tuple[int, int, bool]:
    while first < last and text[first].isspace():
        first += 1
    while last > first and text[last - 1].isspace():
        last -= 1
    if last - first >= 2 and text[first] == '"' and text[last - 1] == '"' and \
            _closes_at_end(text, first, last):
        return first + 1, last - 1, True
    return first, last, False


def _closes_at_end(text: str, first: int, last: int) -> bool:
    """Whether the quote at `first` is closed by the one at `last - 1` (nested calls with
    quotes of their own in between do not close it)."""
    i = first + 1
    while i < last - 1:
        if text.startswith("%(", i):
            end = call_end(text, i + 2)
            if end < 0:
                return False
            i = end
            continue
        if text[i] == "\\":
            i += 2
            continue
        if text[i] == '"':
            return False
        i += 1
    return i == last - 1
