"""The JSON Schemas ln_foxglove advertises (md_json.py), without a manager:
every md type and nesting, dynamic fields in topics and in services, integer ranges, one type
per field (what Foxglove's and Lichtblick's schema reader takes), and samples decoded as the
bridge decodes them conforming to their schema."""

from __future__ import annotations

import ctypes
import json
import math
from pathlib import Path
from typing import Any

import pytest

from links_and_nodes.md_json import encode, root_schema
from links_and_nodes.tools.introspection import values as introspect
from links_and_nodes.tools.introspection.client import load_md, md_class

from .schema_check import conforms

VALID = str(Path(__file__).resolve().parents[2] / "fixtures" / "md" / "valid")


def types_in(schema: Any) -> list[Any]:
    """Every "type" value anywhere in the schema."""
    if isinstance(schema, dict):
        found = [schema["type"]] if "type" in schema else []
        return found + [t for v in schema.values() for t in types_in(v)]
    if isinstance(schema, list):
        return [t for v in schema for t in types_in(v)]
    return []


def sample_of(md_name: str, values: dict[str, Any]) -> dict[str, Any]:
    """`values` packed as a topic sample of `md_name`, decoded as the bridge decodes it."""
    md = load_md(md_name, [VALID])
    message = md_class(md_name, [VALID]).from_dict(values)
    data = ctypes.string_at(ctypes.addressof(message), ctypes.sizeof(message))
    return introspect.decode(md.struct, data)


def test_every_primitive_and_alias() -> None:
    md = load_md("lntest/all_types", [VALID])
    schema = root_schema(md.struct, md.doc)
    props = schema["properties"]
    assert props["i8"] == {"type": "integer", "minimum": -128, "maximum": 127}
    assert props["u64"] == {"type": "integer", "minimum": 0, "maximum": 2**64 - 1}
    assert props["i64"]["minimum"] == -2**63
    assert props["short_alias"]["maximum"] == 2**15 - 1
    assert props["f32"] == {"type": "number"} and props["f64_alias"] == {"type": "number"}
    assert props["c"] == {"type": "string", "maxLength": 1}
    assert props["name"] == {"type": "string", "maxLength": 16,
                             "description": "NUL-padded text"}
    assert props["u8s"] == {"type": "array", "items": {"type": "integer", "minimum": 0,
                                                       "maximum": 255},
                            "minItems": 5, "maxItems": 5}
    assert schema["required"] == [f.name for f in md.struct.fields]
    assert schema["additionalProperties"] is False and schema["title"] == "lntest/all_types"
    assert "NaN" in schema["description"]
    assert all(isinstance(t, str) for t in types_in(schema))
    values = {"c": "x", "i8": -128, "u64": 2**64 - 1, "i64": -2**63, "f32": 0.1,
              "name": "héllo", "u8s": [0, 1, 2, 3, 255], "f32s": [0.5, -1.25, 3.0]}
    sample = sample_of("lntest/all_types", values)
    assert conforms(sample, schema)
    assert {k: sample[k] for k in values} == values  # float32 0.1 decodes as 0.1
    assert json.loads(encode(sample)) == sample


def test_nesting_and_dynamic_fields_in_a_topic_sample() -> None:
    md = load_md("lntest/deep", [VALID])
    schema = root_schema(md.struct, md.doc)
    o = schema["properties"]["o"]
    assert (o["type"], o["minItems"], o["items"]["type"]) == ("array", 2, "object")
    middle = o["items"]["properties"]["m"]
    assert middle["title"] == "lntest/middle"
    assert middle["properties"]["many"]["items"]["properties"]["tag"]["maxLength"] == 4
    # a topic sample carries only the length of a dynamic field: decode shows a text
    assert schema["properties"]["os"]["type"] == "string"
    assert all(isinstance(t, str) for t in types_in(schema))
    sample = sample_of("lntest/deep", {"last": {"a": -3, "b": [1.5, 2.5], "tag": "abcd"}})
    assert conforms(sample, schema)
    assert sample["last"] == {"a": -3, "b": [1.5, 2.5], "tag": "abcd"}


def test_service_sections() -> None:
    md = load_md("robot/set_gains", [])
    request = root_schema(md.sections["request"], md.doc, topic=False, required=False)
    response = root_schema(md.sections["response"], md.doc, topic=False)
    assert request["title"] == "robot/set_gains request"
    assert "required" not in request  # missing request fields are zero or empty
    assert request["properties"]["profile_name"] == {
        "type": "string", "description": "free text, stored in the controller log"}
    assert request["properties"]["kp"]["maxItems"] == 7
    assert response["required"] == ["ok", "message"]
    assert response["description"].startswith("Set the joint impedance gains")
    assert conforms({"ok": 1, "message": "fine"}, response)
    assert conforms({"kp": [1.0] * 7, "profile_name": "soft"}, request)
    with pytest.raises(AssertionError):
        conforms({"kp": [1.0] * 7, "stiffness": 1}, request)


def test_dynamic_arrays_of_messages_in_services() -> None:
    md = load_md("lntest/deep", [VALID])
    schema = root_schema(md.struct, md.doc, topic=False)
    os_ = schema["properties"]["os"]
    assert os_["type"] == "array" and "maxItems" not in os_
    assert os_["items"]["properties"]["note"] == {"type": "string"}  # char*


def test_non_finite_numbers_are_strings() -> None:
    assert json.loads(encode({"x": [math.nan, math.inf, -math.inf, 1.5]})) == \
        {"x": ["NaN", "Infinity", "-Infinity", 1.5]}
    assert encode({"s": "ü", "n": 2}) == '{"s":"ü","n":2}'.encode()
