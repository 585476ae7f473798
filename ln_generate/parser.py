"""Parses the text of one md file into a syntax tree (no type resolution yet).

Grammar, one construct per line (`#` starts a comment):
    service | event                      before any field (defines may precede)
    request | response | connect | call  section headers of services/events
    define LOCAL as "other/md"           import another md as a local type name
    TYPE NAME | TYPE NAME[EXPR] | TYPE* NAME
A repeated section header continues that section (with a warning); a service given
only one of its sections gets the other one empty.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .diagnostics import Diagnostic, Location, MdError
from .model import SECTIONS
from .tokenizer import Token, tokenize

SECTION_KEYWORDS = {name: kind for kind, names in SECTIONS.items() for name in names if name}


@dataclass
class RawDefine:
    alias: str
    alias_loc: Location
    md_name: str
    name_loc: Location


@dataclass
class RawField:
    type_name: str
    type_loc: Location
    dynamic: bool
    name: str
    name_loc: Location
    count: int | None  # static array size, None for scalars and dynamic fields
    comment: str


@dataclass
class RawSection:
    name: str  # "" for a plain message
    loc: Location
    fields: list[RawField] = field(default_factory=list)


@dataclass
class RawFile:
    path: str
    kind: str = "message"
    kind_loc: Location | None = None
    doc: str = ""
    defines: list[RawDefine] = field(default_factory=list)
    sections: list[RawSection] = field(default_factory=list)
    errors: list[Diagnostic] = field(default_factory=list)  # syntax errors; parsing goes on
    warnings: list[Diagnostic] = field(default_factory=list)
    broken_aliases: set[str] = field(default_factory=set)  # defines that had syntax errors


def decode(data: bytes, path: str) -> str:
    """UTF-8 text of an md file; invalid bytes are an error at their position."""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        col = e.start - (data.rfind(b"\n", 0, e.start) + 1) + 1
        raise MdError.at(
            Location(path, line, col),
            f"file is not valid UTF-8 (invalid byte 0x{data[e.start]:02x})",
        ) from None
    return text.removeprefix("\ufeff")


class _ArrayExpr:
    """Recursive-descent evaluator of `[6*6]`-style integer expressions."""

    def __init__(self, tokens: list[Token], file: str, line: int, end_col: int) -> None:
        self.toks = tokens
        self.pos = 0
        self.file = file
        self.line = line
        self.end_col = end_col

    def err(self, col: int, msg: str) -> MdError:
        return MdError.at(Location(self.file, self.line, col), msg)

    def peek(self) -> Token | None:
        return self.toks[self.pos] if self.pos < len(self.toks) else None

    def parse(self) -> int:
        value = self.sum()
        tok = self.peek()
        if tok is not None:
            raise self.err(tok.col, f"unexpected '{tok.text}' in array size")
        return value

    def sum(self) -> int:
        value = self.product()
        while (tok := self.peek()) is not None and tok.text in "+-":
            self.pos += 1
            rhs = self.product()
            value = value + rhs if tok.text == "+" else value - rhs
        return value

    def product(self) -> int:
        value = self.unary()
        while (tok := self.peek()) is not None and tok.text in "*/":
            self.pos += 1
            rhs = self.unary()
            if tok.text == "*":
                value *= rhs
            elif rhs == 0:
                raise self.err(tok.col, "division by zero in array size")
            elif value % rhs:
                raise self.err(tok.col, f"array size {value}/{rhs} is not a whole number")
            else:
                value //= rhs
        return value

    def unary(self) -> int:
        tok = self.peek()
        if tok is not None and tok.text in "+-":
            self.pos += 1
            value = self.unary()
            return -value if tok.text == "-" else value
        return self.atom()

    def atom(self) -> int:
        tok = self.peek()
        if tok is None:
            raise self.err(self.end_col, "incomplete array size expression")
        self.pos += 1
        if tok.kind == "int":
            v = tok.value
            assert isinstance(v, int)
            return v
        if tok.text == "(":
            value = self.sum()
            close = self.peek()
            if close is None or close.text != ")":
                raise self.err(close.col if close else self.end_col, "expected ')' in array size")
            self.pos += 1
            return value
        if tok.kind == "ident":
            raise self.err(tok.col, f"array size must be an integer expression, not '{tok.text}'")
        raise self.err(tok.col, f"unexpected '{tok.text}' in array size")


class _Parser:
    def __init__(self, path: str) -> None:
        self.raw = RawFile(path)
        self.errors: list[Diagnostic] = []
        self.warnings: list[Diagnostic] = []
        self.seen_significant = False
        self.current: RawSection | None = None  # the section new fields go to

    def loc(self, line: int, col: int) -> Location:
        return Location(self.raw.path, line, col)

    def error(self, line: int, col: int, msg: str) -> None:
        self.errors.append(Diagnostic(self.loc(line, col), msg))

    def parse(self, text: str) -> RawFile:
        doc: list[str] = []
        for lineno, line in enumerate(text.split("\n"), start=1):
            try:
                tokens, comment = tokenize(line, self.raw.path, lineno)
            except MdError as e:
                self.errors.extend(e.diagnostics)
                self.seen_significant = True
                continue
            if not tokens:
                if not self.seen_significant and line.strip().startswith("#"):
                    doc.append(comment)
                continue
            try:
                self.line(tokens, comment, lineno, tokens[-1].col + len(tokens[-1].text))
            except MdError as e:
                self.errors.extend(e.diagnostics)
            self.seen_significant = True
        self.raw.doc = "\n".join(doc).strip()
        self.finish()
        self.raw.errors = self.errors
        self.raw.warnings = self.warnings
        return self.raw

    def line(self, toks: list[Token], comment: str, lineno: int, end_col: int) -> None:
        first = toks[0]
        if first.kind != "ident":
            raise MdError.at(self.loc(lineno, first.col), f"expected a type name, got '{first.text}'")
        if first.text == "define" and (len(toks) == 1 or toks[1].kind == "ident"):
            self.define(toks, lineno, end_col)
        elif len(toks) == 1:
            self.keyword(first, lineno)
        else:
            self.field(toks, comment, lineno, end_col)

    def keyword(self, tok: Token, lineno: int) -> None:
        word = tok.text
        if word in ("service", "event"):
            if self.raw.sections or self.raw.kind_loc is not None:
                raise MdError.at(
                    self.loc(lineno, tok.col),
                    f"'{word}' must come before any section or field",
                )
            self.raw.kind = word
            self.raw.kind_loc = self.loc(lineno, tok.col)
            return
        kind = self.raw.kind
        allowed = SECTIONS[kind]
        if word in allowed and word:
            for s in self.raw.sections:
                if s.name == word:  # the original LN merged these; so do we, but say so
                    self.warnings.append(
                        Diagnostic(
                            self.loc(lineno, tok.col),
                            f"section '{word}' appears again (first at line {s.loc.line}); "
                            "its fields are appended to it",
                            "warning",
                        )
                    )
                    self.current = s
                    return
            self.current = RawSection(word, self.loc(lineno, tok.col))
            self.raw.sections.append(self.current)
            return
        if kind == "message":
            if word in SECTION_KEYWORDS:
                owner = SECTION_KEYWORDS[word]
                raise MdError.at(
                    self.loc(lineno, tok.col),
                    f"section keyword '{word}' outside a{'n' if owner == 'event' else ''} "
                    f"{owner} (start the file with '{owner}')",
                )
            raise MdError.at(
                self.loc(lineno, tok.col), f"expected a field 'TYPE NAME' but found only '{word}'"
            )
        expected = " or ".join(f"'{s}'" for s in allowed)
        raise MdError.at(
            self.loc(lineno, tok.col), f"unknown section keyword '{word}' (expected {expected})"
        )

    def define(self, toks: list[Token], lineno: int, end_col: int) -> None:
        if len(toks) > 1 and toks[1].kind == "ident":
            self.raw.broken_aliases.add(toks[1].text)  # until the line proves sound
        for i, (kind, text) in enumerate((("ident", None), ("ident", "as"), ("string", None)), 1):
            if i >= len(toks) or toks[i].kind != kind or (text and toks[i].text != text):
                col = toks[i].col if i < len(toks) else end_col
                raise MdError.at(self.loc(lineno, col), 'expected: define LOCAL_TYPE as "md/name"')
        if len(toks) > 4:
            raise MdError.at(
                self.loc(lineno, toks[4].col), f"unexpected '{toks[4].text}' after define"
            )
        alias, name = toks[1], toks[3]
        for d in self.raw.defines:
            if d.alias == alias.text:
                raise MdError.at(
                    self.loc(lineno, alias.col),
                    f"duplicate define '{alias.text}' (first at line {d.alias_loc.line})",
                )
        md_name = name.value
        assert isinstance(md_name, str)
        self.raw.broken_aliases.discard(alias.text)
        self.raw.defines.append(
            RawDefine(alias.text, self.loc(lineno, alias.col), md_name, self.loc(lineno, name.col + 1))
        )

    def field(self, toks: list[Token], comment: str, lineno: int, end_col: int) -> None:
        type_tok = toks[0]
        i = 1
        dynamic = toks[i].text == "*"
        if dynamic:
            i += 1
        if i >= len(toks) or toks[i].kind != "ident":
            col = toks[i].col if i < len(toks) else end_col
            raise MdError.at(self.loc(lineno, col), f"expected a field name after type '{type_tok.text}'")
        name_tok = toks[i]
        i += 1
        count: int | None = None
        if i < len(toks) and toks[i].text == "[":
            open_tok = toks[i]
            close = next((j for j in range(i + 1, len(toks)) if toks[j].text == "]"), None)
            if close is None:
                raise MdError.at(self.loc(lineno, open_tok.col), "missing ']' after array size")
            if close == i + 1:
                raise MdError.at(self.loc(lineno, toks[close].col), "missing array size")
            if dynamic:
                raise MdError.at(
                    self.loc(lineno, open_tok.col),
                    f"dynamic field '{name_tok.text}' cannot also have a static size",
                )
            count = _ArrayExpr(toks[i + 1 : close], self.raw.path, lineno, toks[close].col).parse()
            if count <= 0:
                raise MdError.at(
                    self.loc(lineno, toks[i + 1].col),
                    f"array size must be positive, got {count}",
                )
            i = close + 1
        if i < len(toks):
            raise MdError.at(
                self.loc(lineno, toks[i].col),
                f"unexpected '{toks[i].text}' after field '{name_tok.text}'",
            )
        if self.raw.kind != "message" and self.current is None:
            first = SECTIONS[self.raw.kind][0]
            raise MdError.at(
                self.loc(lineno, type_tok.col),
                f"field outside a section (a {self.raw.kind} starts with '{first}')",
            )
        if self.current is None:
            self.current = RawSection("", self.loc(lineno, type_tok.col))
            self.raw.sections.append(self.current)
        self.current.fields.append(
            RawField(
                type_tok.text,
                self.loc(lineno, type_tok.col),
                dynamic,
                name_tok.text,
                self.loc(lineno, name_tok.col),
                count,
                comment,
            )
        )

    def finish(self) -> None:
        raw = self.raw
        if raw.kind == "message":
            if not raw.sections and not self.errors:
                what = "only defines, no fields" if raw.defines else "no fields"
                self.error(1, 1, f"empty message definition ({what})")
            return
        assert raw.kind_loc is not None
        if self.errors:
            return  # a missing section is most likely a consequence of those errors
        present = {s.name: s for s in raw.sections}
        names = SECTIONS[raw.kind]
        if raw.kind == "service" and present:
            # As in the original LN, a service without arguments or without a result may
            # leave that section out: it is empty. Sections keep the canonical order.
            raw.sections = [present.get(n) or RawSection(n, raw.kind_loc) for n in names]
            return
        for name in names:
            if name not in present:
                self.errors.append(
                    Diagnostic(raw.kind_loc, f"{raw.kind} has no '{name}' section")
                )


def parse(data: bytes, path: str) -> RawFile:
    """Parse the bytes of one md file; syntax errors are collected in `.errors`.

    Only undecodable bytes raise at once (MdError), since nothing can follow them.
    """
    text = decode(data, path)
    return _Parser(path).parse(text)
