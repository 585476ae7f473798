"""Templates: `template NAME(arg, arg2="default")` headers, their recorded bodies, and
`use_template: NAME(value, ...)` calls that replay a body with the arguments bound."""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from .errors import LineError, Problem, shift
from .lexer import RawLine
from .model import Location
from .text import find_top, unquote

_NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_.\-]*(?:/[A-Za-z_][A-Za-z0-9_.\-]*)*")
_PARAM_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


@dataclass(frozen=True)
class Param:
    name: str
    default: str | None  # raw text, expanded when the template is used
    loc: Location


@dataclass
class Template:
    name: str  # full name, with the name prefixes in effect where it was defined
    loc: Location
    params: list[Param]
    body: list[RawLine] = field(default_factory=list)

    def usage(self) -> str:
        parts = [p.name if p.default is None else f"{p.name}=..." for p in self.params]
        return f"{self.name}({', '.join(parts)})"


def split_call(text: str, loc: Location) -> tuple[str, list[tuple[str, int]] | None]:
    """`NAME(a, "b", c)` -> ("NAME", [("a", offset), ...]); `NAME` -> ("NAME", None).
    Offsets are those of the arguments in `text`; an empty argument stays ("", offset)."""
    m = _NAME_RE.match(text)
    if m is None:
        raise LineError.at(loc, f"expected a template name, got '{text}'")
    name, rest = m.group(), text[m.end():]
    if not rest.strip():
        return name, None
    lead = len(rest) - len(rest.lstrip())
    if not rest.lstrip().startswith("("):
        raise LineError.at(shift(loc, m.end() + lead),
                           f"unexpected '{rest.strip()}' after template name '{name}'")
    open_at = m.end() + lead
    close_at = find_top(text, ")", open_at + 1)
    if close_at < 0:
        raise LineError.at(shift(loc, open_at), "missing ')' after the template arguments")
    if text[close_at + 1:].strip():
        raise LineError.at(shift(loc, close_at + 1),
                           f"unexpected '{text[close_at + 1:].strip()}' after ')'")
    inner = text[open_at + 1:close_at]
    if not inner.strip():
        return name, []
    args = []
    start = 0
    while True:
        end = find_top(inner, ",", start)
        chunk = inner[start:] if end < 0 else inner[start:end]
        lead = len(chunk) - len(chunk.lstrip())
        args.append((chunk.strip(), open_at + 1 + start + lead))
        if end < 0:
            return name, args
        start = end + 1


def parse_header(text: str, loc: Location) -> tuple[str, list[Param]]:
    """The name and parameters of a `template` section header."""
    name, args = split_call(text, loc)
    params: list[Param] = []
    problems = []
    for arg, offset in args or []:
        ploc = shift(loc, offset)
        pname, eq, default = arg.partition("=")
        pname = pname.strip()
        if not _PARAM_RE.match(pname):
            problems.append(Problem(ploc, f"bad template parameter '{arg}' "
                                          "(expected NAME or NAME=DEFAULT)"))
            continue
        if any(p.name == pname for p in params):
            problems.append(Problem(ploc, f"duplicate template parameter '{pname}'"))
            continue
        if not eq and params and params[-1].default is not None:
            problems.append(Problem(ploc, f"template parameter '{pname}' without default "
                                          "after one with a default"))
            continue
        params.append(Param(pname, unquote(default.strip())[0] if eq else None, ploc))
    if problems:
        raise LineError(problems)
    return name, params


def check_arity(template: Template, given: int, loc: Location) -> None:
    most = len(template.params)
    least = sum(1 for p in template.params if p.default is None)
    if least <= given <= most:
        return
    want = str(most) if least == most else f"{least} to {most}"
    raise LineError.at(loc, f"template '{template.name}' takes {want} argument"
                            f"{'' if want == '1' else 's'}, got {given} "
                            f"(usage: {template.usage()})")
