"""Positions between the server, which counts characters (code points) as the reader does,
and the client, which counts units of the position encoding agreed at initialize (UTF-16
unless the client offers UTF-8 or UTF-32 in `general.positionEncodings`).  Every position
the server receives or sends passes through here, with the text of the line it is on."""

from __future__ import annotations

from collections.abc import Sequence

from lsprotocol import types as lsp
from pygls.workspace import PositionCodec


def _line(lines: Sequence[str], number: int) -> str:
    return lines[number] if 0 <= number < len(lines) else ""


def position_to_client(codec: PositionCodec, lines: Sequence[str], pos: lsp.Position
                       ) -> lsp.Position:
    """A position in characters as the client counts it; past the end of the line (or of
    the text) the characters beyond count one unit each."""
    text = _line(lines, pos.line)
    inside = min(pos.character, len(text))
    units = codec.client_num_units(text[:inside]) + pos.character - inside
    return lsp.Position(pos.line, units)


def position_from_client(codec: PositionCodec, lines: Sequence[str], pos: lsp.Position
                         ) -> lsp.Position:
    """A client's position in characters (a position inside a character, such as the
    second half of a UTF-16 surrogate pair, is the character's start)."""
    text = _line(lines, pos.line)
    units = 0
    for index, char in enumerate(text):
        step = codec.client_num_units(char)
        if units + step > pos.character:
            return lsp.Position(pos.line, index)
        units += step
    return lsp.Position(pos.line, len(text) + max(pos.character - units, 0))


def range_to_client(codec: PositionCodec, lines: Sequence[str], r: lsp.Range) -> lsp.Range:
    return lsp.Range(position_to_client(codec, lines, r.start),
                     position_to_client(codec, lines, r.end))


def diagnostics_to_client(codec: PositionCodec, lines: Sequence[str],
                          items: list[lsp.Diagnostic]) -> list[lsp.Diagnostic]:
    for d in items:
        d.range = range_to_client(codec, lines, d.range)
    return items


def symbols_to_client(codec: PositionCodec, lines: Sequence[str],
                      symbols: list[lsp.DocumentSymbol]) -> list[lsp.DocumentSymbol]:
    for s in symbols:
        s.range = range_to_client(codec, lines, s.range)
        s.selection_range = range_to_client(codec, lines, s.selection_range)
        symbols_to_client(codec, lines, list(s.children or []))
    return symbols
