"""`%( )` evaluation of `.lnc` values: defines, builtin defines and builtin functions.

Calls nest (`%(env %(var))`): inner calls are expanded first, then the call's text is
either a name (template argument, builtin or define) or `FUNCTION ARGS`.  Results are
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
from .text import split_args

MAX_DEPTH = 16  # nesting of %( ) calls
FUNCTIONS = ("env", "dirname", "subst", "get_port_from_string")
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
                 manager: str | None) -> None:
        self.env = env
        self.defines: dict[str, str] = dict(fixed)
        self.fixed = frozenset(fixed)  # given by the caller: the files cannot change them
        self.hostname = hostname
        self.manager_override = manager
        self.instance_name: str | None = None
        self.manager: str | None = None  # as written in the instance section
        self.process: tuple[str, str] | None = None  # (name, full name) of the last process
        # Names whose defining line had a problem: a line using them is skipped quietly.
        self.broken: set[str] = set()
        self._poisoned = False

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
        out, _ = self._scan(text, 0, 0, loc, file, args, problems)
        if problems or self._poisoned:
            # A name whose own line failed: that problem is reported already, so this
            # line is skipped without another.
            raise LineError(problems)
        return out

    def _scan(self, text: str, i: int, depth: int, loc: Location, file: str,
              args: Mapping[str, str] | None, problems: list[Problem]) -> tuple[str, int]:
        """Expand from `i`.  Inside a call (depth > 0) stop after its closing `)`.
        Returns the text and the index after it, -1 when the call is not closed."""
        out: list[str] = []
        quoted = False
        parens = 0
        while i < len(text):
            if text.startswith("%(", i):
                if depth >= MAX_DEPTH:
                    raise LineError([*problems, Problem(shift(loc, i),
                                                        f"'%(' nested more than {MAX_DEPTH} deep")])
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
            c = text[i]
            if depth:
                if quoted and c == "\\" and i + 1 < len(text):
                    out.append(text[i:i + 2])
                    i += 2
                    continue
                if c == '"':
                    quoted = not quoted
                elif not quoted and c == "(":
                    parens += 1
                elif not quoted and c == ")":
                    if parens == 0:
                        return "".join(out), i + 1
                    parens -= 1
            out.append(c)
            i += 1
        return "".join(out), -1 if depth else i

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
                problems.append(Problem(loc, self._undefined(name, args)))
                return ""
            return value
        if name not in FUNCTIONS:
            hint = did_you_mean(name, FUNCTIONS)
            problems.append(Problem(loc, f"unknown function '{name}' in '%()'{hint}"))
            return ""
        try:
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
        if name == "dirname":
            need(1, 1, "one argument")
            return os.path.dirname(fargs[0])
        if name == "subst":
            need(3, 3, '3 arguments: "FROM", "TO", "STRING"')
            if not fargs[0]:
                raise ValueError("'subst' cannot replace an empty string")
            return fargs[2].replace(fargs[0], fargs[1])
        need(1, 1, "one argument")
        return str(port_from_string(fargs[0]))
