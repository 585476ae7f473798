"""Reads the Tree-sitter test corpus format (test/corpus/*.txt: a `===` header with the
case's name and attributes, the source, a `---` divider, the expected S-expression) as
`tree-sitter test` does, and normalizes S-expressions the same way for comparison."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

ATTRIBUTES = {":skip", ":error", ":fail-fast", ":cst"}  # :platform/:language: not used here
_FIELD = re.compile(r" [A-Za-z0-9_]+: \(")


@dataclass(frozen=True)
class CorpusCase:
    """One example: where its header starts (1-based line), its source and expectation."""

    file: Path
    line: int
    name: str
    attributes: frozenset[str]
    source: bytes
    expected: str  # normalized

    @property
    def where(self) -> str:
        return f"{self.file}:{self.line}"


def _delimiter(line: str, char: str) -> int:
    """Length of the run of `char` a delimiter line starts with (0: not a delimiter)."""
    length = len(line) - len(line.lstrip(char))
    return length if length >= 3 else 0


def _header(lines: list[str], start: int) -> tuple[str, frozenset[str], int] | None:
    """(name, attributes, first body line) of a header opening at `start`, if one does."""
    if not _delimiter(lines[start], "="):
        return None
    name: list[str] = []
    attributes: set[str] = set()
    for i in range(start + 1, len(lines)):
        text = lines[i].strip()
        if _delimiter(lines[i], "="):
            return (" ".join(name), frozenset(attributes), i + 1) if name else None
        if not text and not attributes:
            return None  # a blank line: this `===` is part of a source, not a header
        if text.split("(")[0] in ATTRIBUTES or text.startswith((":platform(", ":language(")):
            attributes.add(text.split("(")[0])
        elif text and not attributes:
            name.append(text)
    return None


def _case(
    file: Path, line: int, name: str, attributes: frozenset[str], body: list[str]
) -> CorpusCase:
    dividers = [
        (len(t) - len(t.lstrip("-")), i)
        for i, t in enumerate(body)
        if _delimiter(t, "-") and not t.strip("-\r\n")
    ]
    if not dividers:
        raise ValueError(f"{file}:{line}: case {name!r} has no '---' divider")
    longest = max(length for length, _ in dividers)
    divider = max(i for length, i in dividers if length == longest)  # ties: the later one
    source = "".join(body[:divider]).encode()
    source = source.removesuffix(b"\n").removesuffix(b"\r")
    return CorpusCase(file, line, name, attributes, source, normalize("".join(body[divider + 1 :])))


def read_corpus(file: Path) -> list[CorpusCase]:
    """Every example of one corpus file, in file order."""
    # split at "\n" only, keeping "\r": a source may hold carriage returns on purpose
    lines = re.findall(r"[^\n]*\n|[^\n]+$", file.read_bytes().decode("utf-8"))
    headers = []
    i = 0
    while i < len(lines):
        found = _header(lines, i)
        if found is None:
            i += 1
            continue
        headers.append((i, *found))
        i = found[2]
    cases = []
    for k, (start, name, attributes, body_start) in enumerate(headers):
        end = headers[k + 1][0] if k + 1 < len(headers) else len(lines)
        cases.append(_case(file, start + 1, name, attributes, lines[body_start:end]))
    return cases


def normalize(sexp: str) -> str:
    """One space between tokens, none before `)`, `;` comment lines dropped."""
    kept = [line for line in sexp.splitlines() if not line.lstrip().startswith(";")]
    text = " ".join(" ".join(kept).split())
    return text.replace(" )", ")")


def has_fields(sexp: str) -> bool:
    return ": (" in sexp


def strip_fields(sexp: str) -> str:
    """The S-expression without `name: ` field labels (for expectations written without)."""
    return _FIELD.sub(" (", sexp)
