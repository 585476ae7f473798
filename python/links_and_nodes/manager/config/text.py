"""Quote-aware text helpers of the `.lnc` reader: values with their source location,
removing surrounding double quotes, and splitting at separators outside quotes and
`%( )` calls."""

from __future__ import annotations

import re
from dataclasses import dataclass

from .errors import shift
from .model import Location


@dataclass(frozen=True)
class Piece:
    """Raw text of a value as written, before `%()` expansion."""

    text: str
    loc: Location


@dataclass(frozen=True)
class Value:
    """An evaluated value.  `exact` says that `text` is character for character what is
    written at `loc`, so a problem inside it can point at its own column."""

    text: str
    loc: Location
    exact: bool = True

    def at(self, offset: int) -> Location:
        return shift(self.loc, offset) if self.exact else self.loc


def closing_quote(text: str, start: int) -> int:
    """Index of the `"` that closes the one at `start`, or -1; `\\"` does not close."""
    i = start + 1
    while i < len(text):
        if text[i] == "\\" and i + 1 < len(text):
            i += 2
            continue
        if text[i] == '"':
            return i
        i += 1
    return -1


def unquote(text: str) -> tuple[str, bool]:
    """The content of a value written entirely in double quotes (with `\\"` and `\\\\`
    unescaped), and whether quotes were removed; other text is returned unchanged."""
    if len(text) >= 2 and text[0] == '"' and closing_quote(text, 0) == len(text) - 1:
        return unescape(text[1:-1]), True
    return text, False


def unescape(text: str) -> str:
    """The text inside double quotes with `\\"` and `\\\\` unescaped."""
    return re.sub(r'\\(["\\])', r"\1", text)


def find_top(text: str, chars: str, start: int = 0) -> int:
    """Index of the first of `chars` outside double quotes and `%( )` calls, or -1."""
    depth = 0
    i = start
    while i < len(text):
        c = text[i]
        if c == '"':
            end = closing_quote(text, i)
            if end < 0:
                return -1
            i = end + 1
            continue
        if text.startswith("%(", i):
            depth += 1
            i += 2
            continue
        if depth and c == ")":
            depth -= 1
        elif not depth and c in chars:
            return i
        i += 1
    return -1


def split_top(text: str, seps: str) -> list[tuple[str, int]]:
    """Split at any of `seps` outside quotes and calls; each part stripped, with its offset
    in `text`; empty parts are dropped."""
    parts: list[tuple[str, int]] = []
    start = 0
    while True:
        end = find_top(text, seps, start)
        chunk = text[start:] if end < 0 else text[start:end]
        stripped = chunk.strip()
        if stripped:
            parts.append((stripped, start + len(chunk) - len(chunk.lstrip())))
        if end < 0:
            return parts
        start = end + 1


def split_value(value: Value, seps: str = ",") -> list[Value]:
    """The items of a list value, each unquoted, with their own locations."""
    items = []
    for text, offset in split_top(value.text, seps):
        inner, quoted = unquote(text)
        items.append(Value(inner, value.at(offset + int(quoted)), value.exact and not quoted))
    return items


def split_args(text: str) -> list[str]:
    """Comma-separated arguments of a `%()` function, each unquoted; an empty argument
    list gives []."""
    if not text.strip():
        return []
    args = []
    start = 0
    while True:
        end = find_top(text, ",", start)
        chunk = (text[start:] if end < 0 else text[start:end]).strip()
        args.append(unquote(chunk)[0])
        if end < 0:
            return args
        start = end + 1
