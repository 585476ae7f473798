"""Splits one line of a message definition into tokens with 1-based columns.

The md syntax is line oriented, so the parser asks for one line at a time; the
tokenizer also hands back the trailing `#` comment so emitters can keep it.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Literal

from .diagnostics import Location, MdError

TokenKind = Literal["ident", "int", "string", "op"]

_TOKEN_RE = re.compile(
    r"""
    (?P<ws>[ \t\r\f\v]+)
  | (?P<comment>\#.*)
  | (?P<ident>[A-Za-z_][A-Za-z0-9_]*)
  | (?P<int>0[xX][0-9A-Fa-f]+|[0-9]+)(?P<badnum>[A-Za-z0-9_]*)
  | (?P<string>"[^"]*")
  | (?P<unterminated>"[^"]*$)
  | (?P<op>[*\[\]()+\-/])
    """,
    re.VERBOSE,
)


@dataclass(frozen=True)
class Token:
    kind: TokenKind
    text: str
    col: int

    @property
    def value(self) -> str | int:
        if self.kind == "int":
            return int(self.text, 0) if self.text.lower().startswith("0x") else int(self.text)
        if self.kind == "string":
            return self.text[1:-1]
        return self.text


def tokenize(text: str, file: str, line: int) -> tuple[list[Token], str]:
    """Return the tokens of one line and its comment text (without `#`)."""
    tokens: list[Token] = []
    comment = ""
    pos = 0
    while pos < len(text):
        m = _TOKEN_RE.match(text, pos)
        col = pos + 1
        if m is None:
            ch = text[pos]
            shown = repr(ch) if ch.isprintable() else f"U+{ord(ch):04X}"
            raise MdError.at(Location(file, line, col), f"unexpected character {shown}")
        kind = m.lastgroup
        if m.group("badnum"):
            raise MdError.at(
                Location(file, line, col), f"bad number '{m.group('int')}{m.group('badnum')}'"
            )
        if kind == "unterminated":
            raise MdError.at(Location(file, line, col), "unterminated string")
        if kind == "comment":
            comment = m.group()[1:].strip()
            break
        if kind == "int" or kind == "badnum":
            tokens.append(Token("int", m.group("int"), col))
        elif kind != "ws":
            assert kind is not None
            tokens.append(Token(kind, m.group(), col))  # type: ignore[arg-type]
        pos = m.end()
    return tokens, comment
