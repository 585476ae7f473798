"""Between the reader's places (`file:line:col`, 1-based, in characters) and the LSP's
(URIs, 0-based lines and characters), and the word or name under the cursor."""

from __future__ import annotations

import re
from pathlib import Path
from urllib.parse import unquote, urlparse

from lsprotocol import types as lsp

from ...config.model import Location

# How a problem in the output of `pipe_include` names its place (directives.py).
PIPE_FILE_RE = re.compile(r"(?P<file>.*):(?P<line>\d+):(?P<col>\d+): output of pipe_include\Z")
_WORD_RE = re.compile(r"[A-Za-z0-9_.\-/]+")


def uri_to_path(uri: str) -> str:
    parsed = urlparse(uri)
    return unquote(parsed.path) if parsed.scheme == "file" else uri


def path_to_uri(path: str) -> str:
    return Path(path).absolute().as_uri()


def real_place(loc: Location) -> tuple[Location, str]:
    """The place in a real file: a problem in a pipe_include's output is put at the
    directive, with a note saying so."""
    m = PIPE_FILE_RE.match(loc.file)
    if m is None:
        return loc, ""
    at = Location(m["file"], int(m["line"]), int(m["col"]))
    return at, f" (line {loc.line} of the output of pipe_include)"


def token_range(loc: Location, lines: list[str], length: int | None = None) -> lsp.Range:
    """The range from `loc` over `length` characters, or (None) over the word there."""
    line = max(loc.line - 1, 0)
    start = max(loc.col - 1, 0)
    text = lines[line] if line < len(lines) else ""
    if length is None:
        m = re.compile(r"\S+").match(text, start)
        length = len(m.group()) if m else 1
    return lsp.Range(lsp.Position(line, start), lsp.Position(line, start + length))


def to_location(loc: Location, lines: list[str], length: int | None = None) -> lsp.Location:
    return lsp.Location(path_to_uri(loc.file), token_range(loc, lines, length))


def word_at(text: str, line: int, character: int) -> tuple[str, int]:
    """The name-like word around a position and its start column (0-based), or ("", -1)."""
    lines = text.split("\n")
    if line >= len(lines):
        return "", -1
    for m in _WORD_RE.finditer(lines[line]):
        if m.start() <= character <= m.end():
            return m.group(), m.start()
    return "", -1


def covers(loc: Location, length: int, path: str, line: int, character: int) -> bool:
    """Whether the 0-based position lies in `length` characters from `loc` in `path`."""
    return (loc.file == path and loc.line == line + 1
            and loc.col - 1 <= character <= loc.col - 1 + length)
