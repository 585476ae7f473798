"""Parser of wire schemas (*.schema): one file declares one protocol's constants, enums and
payload layouts, and the codecs of every language are generated from it (gen_cpp.py, the
C generator, codec.py at import time).

The format, line comments start with `#` (a comment after an entry is its documentation):

    protocol NAME                       once, first
    str_length u16                      optional, next: the width of the byte count of
                                        `str` (u8, u16 or u32; default u32)
    const NAME = 123 | 0x1f | "text"    an integer or a string constant
    enum NAME BASE [message_types] {    BASE: u8 u16 u32; message_types marks the enum of
        ENTRY = 1                       message numbers: each of its entries needs a
    }                                   `message ENTRY` layout
    flags NAME BASE {                   bits of one integer; in structs each bit is a bool
        bit_name = 1                    member named like the bit
    }
    record Name { FIELD... }            a layout used inside messages
    message ENTRY [from SIDE] [answer REPLY] { FIELD... }
                                        the payload of message type ENTRY; optionally who
                                        sends it and the message type that answers it

A field is `name TYPE [= default]`, TYPE one of

    u8 u16 u32 u64 i32 i64 f64          little-endian numbers
    bool                                u8 that must be 0 or 1
    str | str(LIMIT)                    length (str_length) + UTF-8 bytes, at most LIMIT
                                        (default MAX_FRAME if declared, else what the
                                        length can count) bytes
    bytes | bytes(LIMIT)                u32 length + raw bytes, at most LIMIT
    text                                u32 length + UTF-8 bytes, bounded by the frame
    bytes[SIZE]                         exactly SIZE raw bytes, no length
    list<TYPE>                          u32 count + the items (decoders bound the count by
                                        the bytes left)
    ENUM                                the enum's base integer; decoders refuse other values
    FLAGS                               the base integer; decoders refuse unknown bits
    Record                              the record's fields, inline
    tail                                the rest of the payload, raw (last field only)

LIMIT and SIZE are integers or constant names.  Defaults: numbers, "strings", true/false,
and for a flags field the names of the bits set, joined by `|`.  Errors are SchemaError,
whose text is `file:line:col: message`.

API: `load(path) -> Schema`, `parse(text, path) -> Schema`; `Schema.min_size(type)`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

INTS = {"u8": (1, False), "u16": (2, False), "u32": (4, False), "u64": (8, False),
        "i32": (4, True), "i64": (8, True)}
SCALARS = {**{k: v[0] for k, v in INTS.items()}, "f64": 8, "bool": 1}
U32_MAX = 0xFFFFFFFF


class SchemaError(ValueError):
    """A mistake in a schema file; str() is `file:line:col: message`."""

    def __init__(self, path: str, line: int, col: int, message: str) -> None:
        super().__init__(f"{path}:{line}:{col}: {message}")
        self.path, self.line, self.col, self.message = path, line, col, message


@dataclass(frozen=True)
class Loc:
    path: str
    line: int
    col: int


@dataclass
class Const:
    name: str
    value: int | str
    doc: str
    loc: Loc


@dataclass
class Entry:
    name: str
    value: int
    doc: str
    loc: Loc


@dataclass
class Enum:
    """An enum (kind "enum") or a set of bits (kind "flags") over an integer `base`."""

    name: str
    kind: str
    base: str
    entries: list[Entry]
    doc: str
    loc: Loc
    message_types: bool = False

    def value(self, name: str) -> int | None:
        return next((e.value for e in self.entries if e.name == name), None)


@dataclass
class Type:
    """kind: "int" (name u8..i64), "f64", "bool", "str", "bytes" (limit), "fixed" (size),
    "list" (item), "enum" / "flags" / "record" (ref: the declaration's name), "tail"."""

    kind: str
    name: str
    limit: int | None = None
    size: int | None = None
    item: Type | None = None
    ref: str | None = None
    explicit: bool = False  # str/bytes: the limit was written, not the default

    def __str__(self) -> str:
        if self.kind == "list":
            return f"list<{self.item}>"
        if self.kind == "fixed":
            return f"bytes[{self.size}]"
        return self.name


@dataclass
class Field:
    name: str
    type: Type
    default: int | float | str | bool | list[str] | None
    doc: str
    loc: Loc


@dataclass
class Struct:
    """A record (name as written) or a message (name: its entry of the message type enum;
    `type_name` the CamelCase name of its generated struct or class)."""

    name: str
    kind: str
    type_name: str
    fields: list[Field]
    doc: str
    loc: Loc
    sender: str | None = None  # `from SIDE`
    answer: str | None = None  # `answer REPLY`: a message name


@dataclass
class Schema:
    path: str
    protocol: str
    str_length: str = "u32"  # u8, u16 or u32
    consts: dict[str, Const] = field(default_factory=dict)
    enums: dict[str, Enum] = field(default_factory=dict)  # enums and flags
    records: dict[str, Struct] = field(default_factory=dict)
    messages: dict[str, Struct] = field(default_factory=dict)  # in declaration order

    @property
    def message_enum(self) -> Enum:
        return next(e for e in self.enums.values() if e.message_types)

    def struct(self, name: str) -> Struct:
        return self.records.get(name) or self.messages[name]

    def min_size(self, t: Type) -> int:
        """The fewest bytes a value of `t` takes on the wire."""
        if t.kind in ("int", "f64", "bool"):
            return SCALARS[t.name]
        if t.kind == "str":
            return SCALARS[self.str_length]
        if t.kind in ("bytes", "list", "text"):
            return 4
        if t.kind == "fixed":
            return t.size or 0
        if t.kind in ("enum", "flags"):
            return SCALARS[self.enums[t.ref or ""].base]
        if t.kind == "record":
            return sum(self.min_size(f.type) for f in self.records[t.ref or ""].fields)
        return 0  # tail


def camel(name: str) -> str:
    """SPAWN -> Spawn, RING_CREATE -> RingCreate."""
    return "".join(part.capitalize() for part in name.lower().split("_"))


_TOKEN = re.compile(r"""
    (?P<comment>\#[^\n]*)
  | (?P<nl>\n)
  | (?P<space>[ \t\r]+)
  | (?P<string>"(?:[^"\\\n]|\\.)*")
  | (?P<number>-?(?:0x[0-9a-fA-F]+|\d+(?:\.\d+)?(?:[eE][-+]?\d+)?))
  | (?P<ident>[A-Za-z_][A-Za-z0-9_]*)
  | (?P<punct>[{}<>()\[\]=|])
""", re.VERBOSE)


@dataclass
class _Tok:
    kind: str
    text: str
    loc: Loc
    doc: str = ""  # the comment that ends this token's line


class _Parser:
    def __init__(self, text: str, path: str) -> None:
        self.path = path
        self.toks = self._lex(text)
        self.i = 0

    def _lex(self, text: str) -> list[_Tok]:
        toks: list[_Tok] = []
        line, line_start, pos = 1, 0, 0
        line_toks: list[_Tok] = []
        documented: _Tok | None = None
        doc_line = 0
        while pos < len(text):
            m = _TOKEN.match(text, pos)
            col = pos - line_start + 1
            if not m:
                raise SchemaError(self.path, line, col, f"unexpected character {text[pos]!r}")
            kind = m.lastgroup or ""
            if kind == "nl":
                line, line_start, line_toks = line + 1, m.end(), []
            elif kind == "comment":
                doc = m.group().lstrip("#").strip()
                if line_toks:
                    line_toks[0].doc = doc
                    documented, doc_line = line_toks[0], line
                elif documented is not None and doc_line == line - 1 and pos - line_start > 4:
                    documented.doc += " " + doc  # an indented continuation
                    doc_line = line
            elif kind != "space":
                tok = _Tok(kind, m.group(), Loc(self.path, line, col))
                toks.append(tok)
                line_toks.append(tok)
            pos = m.end()
        toks.append(_Tok("eof", "", Loc(self.path, line, pos - line_start + 1)))
        return toks

    # -- token helpers --

    def peek(self) -> _Tok:
        return self.toks[self.i]

    def next(self) -> _Tok:
        tok = self.toks[self.i]
        self.i += 1
        return tok

    def fail(self, tok: _Tok, message: str) -> SchemaError:
        return SchemaError(tok.loc.path, tok.loc.line, tok.loc.col, message)

    def expect(self, text: str) -> _Tok:
        tok = self.next()
        if tok.text != text:
            raise self.fail(tok, f"expected '{text}', got {self._show(tok)}")
        return tok

    def ident(self, what: str) -> _Tok:
        tok = self.next()
        if tok.kind != "ident":
            raise self.fail(tok, f"expected {what}, got {self._show(tok)}")
        return tok

    @staticmethod
    def _show(tok: _Tok) -> str:
        return "end of file" if tok.kind == "eof" else f"'{tok.text}'"

    # -- grammar --

    def parse(self) -> Schema:
        first = self.peek()
        if first.text != "protocol":
            raise self.fail(first, "a schema starts with 'protocol NAME'")
        self.next()
        schema = Schema(self.path, self.ident("a protocol name").text)
        if self.peek().text == "str_length":
            self.next()
            width = self.ident("u8, u16 or u32")
            if width.text not in ("u8", "u16", "u32"):
                raise self.fail(width, "str_length must be u8, u16 or u32")
            schema.str_length = width.text
        names: dict[str, Loc] = {}
        pending: list[tuple[Struct, _Tok]] = []
        while self.peek().kind != "eof":
            tok = self.next()
            if tok.text == "const":
                c = self.const(schema)
                self.declare(names, c.name, tok)
                schema.consts[c.name] = c
            elif tok.text in ("enum", "flags"):
                e = self.enum(tok, schema)
                self.declare(names, e.name, tok)
                schema.enums[e.name] = e
            elif tok.text in ("record", "message"):
                s = self.struct(tok, schema)
                self.declare(names, (s.kind, s.name) if s.kind == "message" else s.name, tok)
                (schema.records if s.kind == "record" else schema.messages)[s.name] = s
                pending.append((s, tok))
            else:
                raise self.fail(tok, f"expected const, enum, flags, record or message, got "
                                     f"{self._show(tok)}")
        self.check(schema, pending)
        return schema

    def declare(self, names: dict, key: object, tok: _Tok) -> None:
        if key in names:
            loc = names[key]
            raise self.fail(tok, f"{key if isinstance(key, str) else key[1]} is declared "
                                 f"twice (first at line {loc.line})")
        names[key] = tok.loc

    def number(self, tok: _Tok) -> int | float:
        if tok.kind != "number":
            raise self.fail(tok, f"expected a number, got {self._show(tok)}")
        text = tok.text
        if "0x" in text:
            return int(text, 16)
        return float(text) if any(c in text for c in ".eE") else int(text)

    def integer(self, tok: _Tok, schema: Schema) -> int:
        """A literal integer or the name of an integer constant."""
        if tok.kind == "ident":
            c = schema.consts.get(tok.text)
            if c is None or not isinstance(c.value, int):
                raise self.fail(tok, f"{tok.text} is not an integer constant")
            return c.value
        value = self.number(tok)
        if not isinstance(value, int):
            raise self.fail(tok, "expected an integer")
        return value

    def const(self, schema: Schema) -> Const:
        name = self.ident("a constant name")
        self.expect("=")
        tok = self.next()
        value: int | str
        if tok.kind == "string":
            value = _unquote(tok.text)
        else:
            value = self.integer(tok, schema)
        return Const(name.text, value, tok.doc or name.doc, name.loc)

    def enum(self, keyword: _Tok, schema: Schema) -> Enum:
        name = self.ident(f"a {keyword.text} name")
        base = self.ident("a base type (u8, u16, u32)")
        if base.text not in ("u8", "u16", "u32"):
            raise self.fail(base, f"the base of {name.text} must be u8, u16 or u32")
        marker = False
        if self.peek().text == "message_types":
            if keyword.text != "enum":
                raise self.fail(self.peek(), "only an enum can number message types")
            if any(e.message_types for e in schema.enums.values()):
                raise self.fail(self.peek(), "a second enum marked message_types")
            self.next()
            marker = True
        brace = self.expect("{")
        entries: list[Entry] = []
        limit = (1 << (8 * SCALARS[base.text])) - 1
        while self.peek().text != "}":
            tok = self.ident("an entry name or '}'")
            self.expect("=")
            vtok = self.next()
            value = self.integer(vtok, schema)
            if not 0 <= value <= limit:
                raise self.fail(vtok, f"{value} does not fit {base.text}")
            if any(e.name == tok.text for e in entries):
                raise self.fail(tok, f"{tok.text} is declared twice in {name.text}")
            if keyword.text == "flags" and (value == 0 or value & (value - 1)):
                raise self.fail(vtok, "a flag must be a single bit")
            if keyword.text == "flags" and not tok.text.islower():
                raise self.fail(tok, "flag names are lower case: they name bool fields")
            entries.append(Entry(tok.text, value, tok.doc, tok.loc))
        self.next()
        if not entries:
            raise self.fail(brace, f"{name.text} has no entries")
        return Enum(name.text, keyword.text, base.text, entries, keyword.doc or brace.doc,
                    name.loc, marker)

    def struct(self, keyword: _Tok, schema: Schema) -> Struct:
        name = self.ident(f"a {keyword.text} name")
        attrs: dict[str, str] = {}
        while keyword.text == "message" and self.peek().text in ("from", "answer"):
            key = self.next()
            if key.text in attrs:
                raise self.fail(key, f"'{key.text}' given twice")
            attrs[key.text] = self.ident(f"a name after '{key.text}'").text
        brace = self.expect("{")
        fields: list[Field] = []
        while self.peek().text != "}":
            ftok = self.ident("a field name or '}'")
            if any(f.name == ftok.text for f in fields):
                raise self.fail(ftok, f"field {ftok.text} is declared twice")
            t = self.type(schema)
            default = None
            if self.peek().text == "=":
                self.next()
                default = self.default(t, schema)
            if fields and fields[-1].type.kind == "tail":
                raise self.fail(ftok, "a tail must be the last field")
            fields.append(Field(ftok.text, t, default, ftok.doc, ftok.loc))
        self.next()
        type_name = camel(name.text) if keyword.text == "message" else name.text
        if keyword.text == "record" and not name.text[:1].isupper():
            raise self.fail(name, "record names are CamelCase")
        return Struct(name.text, keyword.text, type_name, fields,
                      keyword.doc or brace.doc, name.loc, attrs.get("from"),
                      attrs.get("answer"))

    def type(self, schema: Schema) -> Type:
        tok = self.ident("a type")
        t = tok.text
        if t in INTS:
            return Type("int", t)
        if t in ("f64", "bool", "tail", "text"):
            return Type(t, t)
        if t in ("str", "bytes"):
            width = schema.str_length if t == "str" else "u32"
            limit = min(int(schema.consts["MAX_FRAME"].value), U32_MAX) \
                if "MAX_FRAME" in schema.consts else U32_MAX
            limit = min(limit, (1 << (8 * SCALARS[width])) - 1)
            explicit = False
            if self.peek().text == "(":
                self.next()
                limit = self.integer(self.next(), schema)
                self.expect(")")
                explicit = True
            elif t == "bytes" and self.peek().text == "[":
                self.next()
                size = self.integer(self.next(), schema)
                self.expect("]")
                return Type("fixed", "bytes", size=size)
            return Type(t, t, limit=int(limit), explicit=explicit)
        if t == "list":
            self.expect("<")
            item = self.type(schema)
            if item.kind == "tail":
                raise self.fail(tok, "a list of tails")
            self.expect(">")
            return Type("list", "list", item=item)
        if t in schema.enums:
            return Type(schema.enums[t].kind, t, ref=t)
        if t in schema.records:
            return Type("record", t, ref=t)
        raise self.fail(tok, f"unknown type {t} (records and enums must be declared first)")

    def default(self, t: Type, schema: Schema) -> int | float | str | bool | list[str]:
        tok = self.next()
        if t.kind == "flags":
            bits = [tok]
            while self.peek().text == "|":
                self.next()
                bits.append(self.next())
            flags = schema.enums[t.ref or ""]
            for b in bits:
                if flags.value(b.text) is None:
                    raise self.fail(b, f"{flags.name} has no bit {b.text}")
            return [b.text for b in bits]
        if t.kind in ("str", "text") and tok.kind == "string":
            return _unquote(tok.text)
        if t.kind == "bool" and tok.text in ("true", "false"):
            return tok.text == "true"
        if t.kind == "f64" and tok.kind == "number":
            return float(self.number(tok))
        if t.kind == "int":
            value = self.integer(tok, schema)
            size, signed = INTS[t.name]
            lo, hi = (-(1 << (8 * size - 1)), (1 << (8 * size - 1)) - 1) if signed \
                else (0, (1 << (8 * size)) - 1)
            if not lo <= value <= hi:
                raise self.fail(tok, f"default {value} does not fit {t.name}")
            return value
        if t.kind == "enum" and tok.kind == "ident":
            if schema.enums[t.ref or ""].value(tok.text) is None:
                raise self.fail(tok, f"{t.ref} has no entry {tok.text}")
            return tok.text
        raise self.fail(tok, f"{self._show(tok)} is no default for a {t}")

    def check(self, schema: Schema, pending: list[tuple[Struct, _Tok]]) -> None:
        enums = [e for e in schema.enums.values() if e.message_types]
        if not enums:
            raise SchemaError(self.path, 1, 1, "no enum is marked message_types")
        msg = enums[0]
        for s, _ in pending:
            if s.kind == "message" and msg.value(s.name) is None:
                raise SchemaError(s.loc.path, s.loc.line, s.loc.col,
                                  f"message {s.name} is not an entry of {msg.name}")
        for s, _ in pending:
            if s.answer is not None and s.answer not in schema.messages:
                raise SchemaError(s.loc.path, s.loc.line, s.loc.col,
                                  f"{s.name} is answered by {s.answer}, which is no message")
        for e in msg.entries:
            if e.name not in schema.messages:
                raise SchemaError(e.loc.path, e.loc.line, e.loc.col,
                                  f"{msg.name} entry {e.name} has no message layout")
        values: dict[int, str] = {}
        for e in msg.entries:
            if e.value in values:
                raise SchemaError(e.loc.path, e.loc.line, e.loc.col,
                                  f"message types {values[e.value]} and {e.name} share "
                                  f"the number {e.value}")
            values[e.value] = e.name
        for s in schema.records.values():
            for f in s.fields:
                if f.type.kind == "tail":
                    raise SchemaError(f.loc.path, f.loc.line, f.loc.col,
                                      "a tail belongs to a message, not a record")


def _unquote(text: str) -> str:
    return bytes(text[1:-1], "utf-8").decode("unicode_escape")


def parse(text: str, path: str = "<schema>") -> Schema:
    """The schema in `text`; SchemaError (file:line:col) for any mistake."""
    return _Parser(text, path).parse()


def load(path: str | Path) -> Schema:
    """The schema in file `path`."""
    return parse(Path(path).read_text(encoding="utf-8"), str(path))


DAEMON_SCHEMA = Path(__file__).with_name("daemon.schema")
CLIENT_SCHEMA = Path(__file__).with_name("client.schema")
