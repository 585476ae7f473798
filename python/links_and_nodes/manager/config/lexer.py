"""Splits the text of one `.lnc` file into logical lines.

Removes blank lines and `#` comments (a `#` inside double quotes is text), and joins a
`KEY: [` line with the lines of its block up to a line holding only `]`.  Inside a
block, lines starting with `#` are skipped but a `#` after text is kept.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from .errors import Problem
from .model import Location
from .text import closing_quote

SECTION_WORDS = ("instance", "defines", "hosts", "node_map", "network", "topics", "process",
                 "state", "group", "template", "process_template", "logger", "access")
_HEADER_RE = re.compile(r"\s*(" + "|".join(SECTION_WORDS) + r")(\s|$)(?!\s*:)")
_OPEN_RE = re.compile(r":\s*\[\Z")
_CLOSE_RE = re.compile(r"\s*\]\s*(#.*)?\Z")


@dataclass(frozen=True)
class BlockLine:
    text: str  # stripped
    loc: Location


@dataclass(frozen=True)
class RawLine:
    """One logical line: text without comment and surrounding blanks, starting at `loc`.
    For a `KEY: [` line, `text` ends at the colon and `block` holds the block's lines."""

    text: str
    loc: Location
    block: tuple[BlockLine, ...] | None = None
    block_loc: Location | None = None  # of the `[`
    broken: bool = False  # its problem is reported already; only its key is of interest

    def sub(self, offset: int) -> RawLine:
        """The rest of this line from `offset` on (for `ifdef NAME: LINE`)."""
        rest = self.text[offset:]
        lead = len(rest) - len(rest.lstrip())
        loc = Location(self.loc.file, self.loc.line, self.loc.col + offset + lead)
        return RawLine(rest.strip(), loc, self.block, self.block_loc, self.broken)


def decode(data: bytes, file: str) -> tuple[str, Problem | None]:
    """UTF-8 text of a file (without BOM).  The first invalid byte is a problem at its
    place; the text is still returned (with U+FFFD for bad bytes) so the rest is checked."""
    try:
        return data.decode("utf-8").removeprefix("\ufeff"), None
    except UnicodeDecodeError as exc:
        start = data.rfind(b"\n", 0, exc.start) + 1
        line = data.count(b"\n", 0, exc.start) + 1
        col = len(data[start:exc.start].decode("utf-8", "replace")) + 1
        text = data.decode("utf-8", "replace").removeprefix("\ufeff")
        return text, Problem(Location(file, line, col),
                             f"file is not valid UTF-8 (byte 0x{data[exc.start]:02x})")


def strip_comment(text: str) -> tuple[str, int]:
    """Text before a `#` outside double quotes, and the index of an unclosed quote or -1."""
    i = 0
    while i < len(text):
        c = text[i]
        if c == '"':
            end = closing_quote(text, i)
            if end < 0:
                return text, i
            i = end + 1
            continue
        if c == "#":
            return text[:i], -1
        i += 1
    return text, -1


def lex(text: str, file: str) -> tuple[list[RawLine], list[Problem]]:
    lines = [line.removesuffix("\r") for line in text.split("\n")]
    out: list[RawLine] = []
    problems: list[Problem] = []
    i = 0
    while i < len(lines):
        number = i + 1
        body, open_quote = strip_comment(lines[i])
        i += 1
        stripped = body.strip()
        if not stripped:
            continue
        loc = Location(file, number, len(body) - len(body.lstrip()) + 1)
        if open_quote >= 0:
            problems.append(Problem(Location(file, number, open_quote + 1),
                                    "unterminated double quote"))
            out.append(RawLine(stripped, loc, broken=True))
            continue
        m = _OPEN_RE.search(stripped)
        if m is None:
            out.append(RawLine(stripped, loc))
            continue
        bracket = Location(file, number, loc.col + len(stripped) - 1)
        block, end = _block(lines, i, file)
        if end is None:
            problems.append(Problem(bracket, "unterminated '[' block (no line with only ']')"))
            out.append(RawLine(stripped[:m.start() + 1], loc, (), bracket, broken=True))
            i = _resume(lines, i)
            continue
        out.append(RawLine(stripped[:m.start() + 1], loc, block, bracket))
        i = end + 1
    return out, problems


def _block(lines: list[str], start: int, file: str) -> tuple[tuple[BlockLine, ...], int | None]:
    """The lines of a block from index `start` and the index of its `]` (None: missing)."""
    content = []
    for j in range(start, len(lines)):
        raw = lines[j]
        if _CLOSE_RE.match(raw):
            return tuple(content), j
        stripped = raw.strip()
        if stripped and not stripped.startswith("#"):
            col = len(raw) - len(raw.lstrip()) + 1
            content.append(BlockLine(stripped, Location(file, j + 1, col)))
    return tuple(content), None


def _resume(lines: list[str], start: int) -> int:
    """Where to go on after an unterminated block: the next section header, so that the
    rest of the file is still checked."""
    for j in range(start, len(lines)):
        if _HEADER_RE.match(lines[j]):
            return j
    return len(lines)
