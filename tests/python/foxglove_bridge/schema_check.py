"""A checker of values against the JSON Schema subset ln_foxglove writes (object, array,
number, integer, string; properties, required, additionalProperties, item counts, integer
ranges, string lengths), for the tests: written here so that the tests need no validator
package and fail on anything the subset does not describe."""

from __future__ import annotations

from typing import Any

_KNOWN = {"$schema", "type", "title", "description", "properties", "required",
          "additionalProperties", "items", "minItems", "maxItems", "minimum", "maximum",
          "maxLength"}


def conforms(value: Any, schema: dict[str, Any], where: str = "$") -> bool:
    """True, or AssertionError naming the first place that does not fit."""
    unknown = set(schema) - _KNOWN
    assert not unknown, f"{where}: schema keywords outside the subset: {unknown}"
    kind = schema["type"]
    if kind == "object":
        assert isinstance(value, dict), f"{where}: not an object: {value!r}"
        props = schema["properties"]
        missing = set(schema.get("required", [])) - set(value)
        assert not missing, f"{where}: missing {missing}"
        if schema.get("additionalProperties") is False:
            extra = set(value) - set(props)
            assert not extra, f"{where}: not in the schema: {extra}"
        for name, item in value.items():
            conforms(item, props[name], f"{where}.{name}")
    elif kind == "array":
        assert isinstance(value, list), f"{where}: not an array: {value!r}"
        assert schema.get("minItems", 0) <= len(value) <= schema.get("maxItems", len(value)), \
            f"{where}: {len(value)} items"
        for i, item in enumerate(value):
            conforms(item, schema["items"], f"{where}[{i}]")
    elif kind == "number":
        assert isinstance(value, (int, float)) and not isinstance(value, bool), \
            f"{where}: not a number: {value!r}"
    elif kind == "integer":
        assert isinstance(value, int) and not isinstance(value, bool), \
            f"{where}: not an integer: {value!r}"
        assert schema["minimum"] <= value <= schema["maximum"], f"{where}: {value} out of range"
    elif kind == "string":
        assert isinstance(value, str), f"{where}: not a string: {value!r}"
        assert len(value) <= schema.get("maxLength", len(value)), f"{where}: too long"
    else:
        raise AssertionError(f"{where}: type {kind!r} outside the subset")
    return True
