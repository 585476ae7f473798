"""JSON Schemas of message definitions, for Foxglove channels and services (docs/webui.md,
"Foxglove and Lichtblick").

The schema describes the JSON that introspect.decode gives for a topic sample and that
service calls take and give: numbers (integers with their range), char fields as strings,
static arrays with their length, nested mds as objects.  Every field is required and no other
is allowed.  Only one "type" per field: Foxglove's and Lichtblick's schema reader takes no
lists of types.  JSON has no NaN or infinities: those come as the strings "NaN", "Infinity",
"-Infinity" (as `topic echo --json` prints them), which the schema notes in its description.
"""

from __future__ import annotations

from typing import Any

from ln_generate.model import Field, Primitive, Struct

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
