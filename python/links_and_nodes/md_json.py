"""The JSON form of md samples, one home for ln_foxglove (docs/webui.md, "Foxglove and
Lichtblick") and the `json` encoding of recordings (docs/recording.md, "Encodings"): the JSON
Schema of an md, a sample's compact JSON, and that JSON packed back into the md's bytes.

The schema describes the JSON that introspect.decode gives for a topic sample and that
service calls take and give: numbers (integers with their range), char fields as strings,
static arrays with their length, nested mds as objects.  Every field is required and no other
is allowed.  Only one "type" per field: Foxglove's and Lichtblick's schema reader takes no
lists of types.  JSON has no NaN or infinities: those come as the strings "NaN", "Infinity",
"-Infinity" (as `topic echo --json` prints them), which the schema notes in its description.
to_bytes() is exact for every number (float32 as the shortest decimal that reads back as the
same float32, float64 as repr); not kept are NaN payload bits and sign, and a char field's
bytes after its first NUL or that are not UTF-8.
"""

from __future__ import annotations

import json
import math
import struct
from typing import Any

from ln_generate.model import Field, Primitive, Struct

from .tools.introspection import values as fmt

SCHEMA_ENCODING = "jsonschema"
DRAFT = "https://json-schema.org/draft/2020-12/schema"
NON_FINITE = ("non-finite values come as the strings \"NaN\", \"Infinity\", \"-Infinity\"")


def _int_range(prim: Primitive) -> tuple[int, int]:
    bits = prim.size * 8
    if prim.kind == "uint":
        return 0, (1 << bits) - 1
    return -(1 << (bits - 1)), (1 << (bits - 1)) - 1


def _primitive(prim: Primitive) -> dict[str, Any]:
    if prim.kind == "float":
        return {"type": "number"}
    low, high = _int_range(prim)
    return {"type": "integer", "minimum": low, "maximum": high}


def _described(schema: dict[str, Any], doc: str) -> dict[str, Any]:
    if doc:
        schema["description"] = doc
    return schema


def _field(f: Field, topic: bool, required: bool) -> dict[str, Any]:
    if f.kind == "dynamic" and topic:
        return {"type": "string", "description": "dynamic field: a topic sample carries only "
                "its length, shown in this text"}
    if isinstance(f.type, Struct):
        element = struct_schema(f.type, topic, required)
    elif f.type.kind == "char":
        text: dict[str, Any] = {"type": "string"}
        if f.kind != "dynamic":
            text["maxLength"] = f.count  # bytes of UTF-8: at most as many characters
        return _described(text, f.doc)
    else:
        element = _primitive(f.type)
    if f.kind == "scalar":
        return _described(element, f.doc)
    array: dict[str, Any] = {"type": "array", "items": element}
    if f.kind == "array":
        array["minItems"] = array["maxItems"] = f.count
    return _described(array, f.doc)


def struct_schema(layout: Struct, topic: bool = True, required: bool = True
                  ) -> dict[str, Any]:
    """The object schema of one record.  `topic`: as a topic sample (a dynamic field is the
    text introspect.decode puts there), else as a service request/response (a dynamic field
    is an array, or a string for char).  `required`: every field is there (not so in a
    request, whose missing fields are zero or empty)."""
    schema: dict[str, Any] = {
        "type": "object", "title": layout.md_name if layout.section is None
        else f"{layout.md_name} {layout.section}",
        "properties": {f.name: _field(f, topic, required) for f in layout.fields},
        "additionalProperties": False}
    if required:
        schema["required"] = [f.name for f in layout.fields]
    if any(_has_float(f) for f in layout.fields):
        schema["description"] = NON_FINITE
    return schema


def _has_float(f: Field) -> bool:
    return isinstance(f.type, Primitive) and f.type.kind == "float"


def root_schema(layout: Struct, doc: str = "", topic: bool = True, required: bool = True
                ) -> dict[str, Any]:
    """struct_schema with `$schema` and the md's documentation in front."""
    schema = {"$schema": DRAFT, **struct_schema(layout, topic, required)}
    if doc:
        schema["description"] = doc + ("\n" + schema["description"]
                                       if "description" in schema else "")
    return schema


# ---- samples --------------------------------------------------------------------------------
def encode(value: Any) -> bytes:
    """Compact JSON of a decoded sample; NaN and infinities as strings (introspect.jsonable)."""
    try:
        text = json.dumps(value, separators=(",", ":"), ensure_ascii=False, allow_nan=False)
    except ValueError:
        text = json.dumps(fmt.jsonable(value), separators=(",", ":"), ensure_ascii=False)
    return text.encode()


_NON_FINITE = {"NaN": math.nan, "Infinity": math.inf, "-Infinity": -math.inf}


class JsonValueError(ValueError):
    """JSON that is not a sample of the md: the text names the field path and why."""


def to_bytes(layout: Struct, values: Any) -> bytes:
    """The packed sample of `layout` whose decoded form (introspect.decode) is `values`; a
    missing, extra or out-of-range field raises JsonValueError naming its path."""
    buf = bytearray(layout.size)
    _pack_struct(layout, values, buf, 0, "")
    return bytes(buf)


def _pack_struct(layout: Struct, values: Any, buf: bytearray, base: int, where: str) -> None:
    if not isinstance(values, dict):
        raise JsonValueError(f"{where or 'the sample'}: an object of md '{layout.md_name}' "
                             f"expected, got {type(values).__name__}")
    names = {f.name for f in layout.fields}
    extra = [k for k in values if k not in names]
    if extra:
        raise JsonValueError(f"{where or 'the sample'}: md '{layout.md_name}' has no field "
                             f"'{extra[0]}'")
    for f in layout.fields:
        path = f"{where}.{f.name}" if where else f.name
        if f.name not in values:
            raise JsonValueError(f"{path}: missing")
        _pack_field(f, values[f.name], buf, base + f.offset, path)


def _pack_field(f: Field, value: Any, buf: bytearray, offset: int, where: str) -> None:
    if f.kind == "dynamic":
        raise JsonValueError(f"{where}: a dynamic field, which a topic sample does not carry")
    items = [value] if f.kind == "scalar" else value
    if f.kind != "scalar" and not (isinstance(f.type, Primitive) and f.type.kind == "char"):
        if not isinstance(value, list) or len(value) != f.count:
            raise JsonValueError(f"{where}: an array of {f.count} values expected")
    if isinstance(f.type, Struct):
        for i, item in enumerate(items):
            _pack_struct(f.type, item, buf, offset + i * f.type.size, f"{where}[{i}]"
                         if f.kind != "scalar" else where)
        return
    if f.type.kind == "char":
        if not isinstance(value, str):
            raise JsonValueError(f"{where}: a string expected")
        raw = value.encode()
        if len(raw) > f.count:
            raise JsonValueError(f"{where}: {len(raw)} bytes of UTF-8, the field holds "
                                 f"{f.count}")
        buf[offset:offset + len(raw)] = raw
        return
    code = fmt._CODES[f.type.name]
    if f.type.kind == "float":
        items = [_NON_FINITE.get(v, v) if isinstance(v, str) else v for v in items]
    try:
        struct.pack_into(f"<{len(items)}{code}", buf, offset, *items)
    except struct.error as exc:
        raise JsonValueError(f"{where}: not {f.type.name} values: {exc}") from None
