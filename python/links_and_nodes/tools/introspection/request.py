"""The request of `service call` (docs/introspection.md): text in a YAML-like flow style
(`kp: [1, 2], profile_name: "soft"`, optionally in braces, also across lines) or JSON,
parsed into plain values, then checked against the request section of the service's
message definition and brought into the shape LnStruct.update takes.  Every error is one
line that names the column (and line) of the bad spot, or the field."""

from __future__ import annotations

import json
import math
from typing import Any

from ln_generate.model import Field, Primitive, Struct

_INT_RANGES = {"int8_t": (-1 << 7, (1 << 7) - 1), "uint8_t": (0, 255),
               "int16_t": (-1 << 15, (1 << 15) - 1), "uint16_t": (0, (1 << 16) - 1),
               "int32_t": (-1 << 31, (1 << 31) - 1), "uint32_t": (0, (1 << 32) - 1),
               "int64_t": (-1 << 63, (1 << 63) - 1), "uint64_t": (0, (1 << 64) - 1)}
_WORDS = {"true": True, "false": False, "null": None, "~": None, "nan": math.nan,
          "inf": math.inf, "+inf": math.inf, "-inf": -math.inf}
_STOP = ",:[]{}\n"


class RequestTextError(ValueError):
    """Request text that is not a mapping of fields, or values that do not fit the md."""


class _Parser:
    def __init__(self, text: str) -> None:
        self.text = text
        self.pos = 0

    def fail(self, message: str, pos: int | None = None) -> RequestTextError:
        pos = self.pos if pos is None else pos
        line = self.text.count("\n", 0, pos) + 1
        column = pos - (self.text.rfind("\n", 0, pos) + 1) + 1
        where = f"line {line}, column {column}" if "\n" in self.text.strip() \
            else f"column {column}"
        found = self.text[pos:pos + 1]
        seen = f", found {found!r}" if found and found != "\n" else \
            ", found the end of the line" if found else ", found the end"
        return RequestTextError(f"bad request text at {where}: {message}{seen}")

    def blank(self, newlines: bool = True) -> None:
        while self.pos < len(self.text) and (self.text[self.pos] in " \t\r"
                                             or (newlines and self.text[self.pos] == "\n")):
            self.pos += 1
        if self.pos < len(self.text) and self.text[self.pos] == "#":  # a comment to the EOL
            while self.pos < len(self.text) and self.text[self.pos] != "\n":
                self.pos += 1
            self.blank(newlines)

    def peek(self) -> str:
        return self.text[self.pos:self.pos + 1]

    def document(self) -> dict[str, Any]:
        self.blank()
        if self.peek() == "{":
            result = self.mapping()
            self.blank()
        else:
            result = self.items(end="")
        if self.pos < len(self.text):
            raise self.fail("expected ',' or the end of the request")
        return result

    def items(self, end: str) -> dict[str, Any]:
        """`key: value` items separated by ',' or line breaks, until `end` (or the text's
        end for "")."""
        result: dict[str, Any] = {}
        while True:
            self.blank()
            if self.peek() == end or (not end and self.pos >= len(self.text)):
                return result
            start = self.pos
            key = self.key()
            if key in result:
                raise self.fail(f"field {key!r} given twice", start)
            self.blank(newlines=False)
            if self.peek() != ":":
                raise self.fail(f"expected ':' after {key!r}")
            self.pos += 1
            self.blank()
            result[key] = self.value()
            self.blank(newlines=False)
            if self.peek() in (",", "\n"):
                self.pos += 1
            elif self.peek() != end and not (not end and self.pos >= len(self.text)):
                raise self.fail("expected ',' or a line break between fields"
                                + (f" or '{end}'" if end else ""))

    def key(self) -> str:
        if self.peek() in ("'", '"'):
            return self.string()
        start = self.pos
        while self.pos < len(self.text) and (self.text[self.pos].isalnum()
                                             or self.text[self.pos] == "_"):
            self.pos += 1
        if start == self.pos:
            raise self.fail("expected a field name")
        return self.text[start:self.pos]

    def mapping(self) -> dict[str, Any]:
        self.pos += 1  # {
        result = self.items(end="}")
        self.pos += 1
        return result

    def sequence(self) -> list[Any]:
        self.pos += 1  # [
        result: list[Any] = []
        while True:
            self.blank()
            if self.peek() == "]":
                self.pos += 1
                return result
            result.append(self.value())
            self.blank()
            if self.peek() == ",":
                self.pos += 1
            elif self.peek() != "]":
                raise self.fail("expected ',' or ']' in a list")

    def value(self) -> Any:
        c = self.peek()
        if c == "{":
            return self.mapping()
        if c == "[":
            return self.sequence()
        if c in ("'", '"'):
            return self.string()
        start = self.pos
        while self.pos < len(self.text) and self.text[self.pos] not in _STOP:
            self.pos += 1
        word = self.text[start:self.pos].rstrip(" \t\r")
        self.pos = start + len(word)
        if not word:
            raise self.fail("expected a value", start)
        if self.peek() == ":" and word.split()[-1] != word:  # `a: 1 b: 2`: a missing ','
            raise self.fail("expected ',' or a line break between fields",
                            start + len(word) - len(word.split()[-1]))
        return _scalar(word)

    def string(self) -> str:
        quote, start = self.peek(), self.pos
        if quote == '"':
            try:
                value, end = json.decoder.scanstring(self.text, self.pos + 1)
            except json.JSONDecodeError as exc:
                raise self.fail(f"bad string: {exc.msg}", exc.pos) from None
            self.pos = end
            return value
        end = self.text.find("'", self.pos + 1)
        while end != -1 and self.text.startswith("''", end):  # YAML: '' is one quote
            end = self.text.find("'", end + 2)
        if end == -1:
            raise self.fail("string not closed", start)
        self.pos = end + 1
        return self.text[start + 1:end].replace("''", "'")


def _scalar(word: str) -> Any:
    lower = word.lower()
    if lower in _WORDS:
        return _WORDS[lower]
    try:
        return int(word, 0)
    except ValueError:
        pass
    try:
        return float(word)
    except ValueError:
        return word  # a bare string, as in YAML


def parse(text: str) -> dict[str, Any]:
    """The fields of a request text (YAML-like flow style or JSON); RequestTextError with
    the column of the bad spot."""
    return _Parser(text).document()


# ---- checking against the md -------------------------------------------------------------
def _fields(layout: Struct) -> str:
    return ", ".join(f.name for f in layout.fields) or "none"


def conform(layout: Struct, values: dict[str, Any], where: str = "") -> dict[str, Any]:
    """`values` checked against `layout` (a request section) and in the shape
    LnStruct.update takes; missing fields stay zero or empty.  A message of exactly one
    field may be given as that field's value (`constraints: ["a", "b"]` for an array of
    ln/string)."""
    known = {f.name: f for f in layout.fields}
    out: dict[str, Any] = {}
    for name, value in values.items():
        field = known.get(name)
        if field is None:
            prefix = f"{where}: " if where else ""
            raise RequestTextError(f"{prefix}md {layout.md_name!r} has no field {name!r} "
                                   f"(its fields: {_fields(layout)})")
        out[name] = _field(field, value, f"{where}.{name}" if where else name)
    return out


def _plain(value: Any) -> Any:
    """Tuples and numpy arrays as lists, numpy numbers as Python numbers (the API takes
    them)."""
    if isinstance(value, tuple):
        return list(value)
    if not isinstance(value, str | bytes | dict | list) and hasattr(value, "tolist"):
        return value.tolist()
    return value


def _field(field: Field, value: Any, where: str) -> Any:
    ftype = field.type
    value = _plain(value)
    if isinstance(ftype, Primitive) and ftype.kind == "char" and field.kind != "scalar":
        if not isinstance(value, str):
            raise RequestTextError(f"field {where!r}: expected a string, not {_what(value)}")
        size = len(value.encode("utf-8"))
        if field.kind == "array" and size > field.count:
            raise RequestTextError(f"field {where!r}: {size} bytes do not fit in "
                                   f"char[{field.count}]")
        return value
    if field.kind == "scalar":
        return _element(ftype, value, where)
    if not isinstance(value, list):
        raise RequestTextError(f"field {where!r}: expected a list, not {_what(value)}")
    if field.kind == "array" and len(value) != field.count:
        raise RequestTextError(f"field {where!r}: expected {field.count} values, got "
                               f"{len(value)}")
    return [_element(ftype, v, f"{where}[{i}]") for i, v in enumerate(value)]


def _element(ftype: Primitive | Struct, value: Any, where: str) -> Any:
    value = _plain(value)
    if isinstance(ftype, Struct):
        if isinstance(value, dict):
            return conform(ftype, value, where)
        if len(ftype.fields) == 1:
            only = ftype.fields[0]
            return {only.name: _field(only, value, f"{where}.{only.name}")}
        raise RequestTextError(f"field {where!r}: expected a mapping of the fields of "
                               f"{ftype.md_name!r} ({_fields(ftype)}), not {_what(value)}")
    if ftype.kind == "char":
        if not isinstance(value, str) or len(value.encode("utf-8")) > 1:
            raise RequestTextError(f"field {where!r}: expected one character, not "
                                   f"{_what(value)}")
        return value
    if isinstance(value, bool):
        value = int(value)
    if ftype.kind == "float":
        if not isinstance(value, int | float):
            raise RequestTextError(f"field {where!r}: expected a number, not {_what(value)}")
        return float(value)
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    if not isinstance(value, int):
        raise RequestTextError(f"field {where!r}: expected an integer ({ftype.name}), not "
                               f"{_what(value)}")
    low, high = _INT_RANGES[ftype.name]
    if not low <= value <= high:
        raise RequestTextError(f"field {where!r}: {value} is out of range for {ftype.name} "
                               f"({low}..{high})")
    return value


def _what(value: Any) -> str:
    if isinstance(value, str):
        return f"the string {value!r}"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, dict):
        return "a mapping"
    if value is None:
        return "null"
    return repr(value)
