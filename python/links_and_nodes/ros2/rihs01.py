"""The RIHS01 type hash of ROS 2 (REP-2011, rosidl_generator_type_description): SHA-256 of the
canonical JSON of a type description: the type and every type it references (sorted by
name), each field as name + {type_id, capacity, string_capacity, nested_type_name}, default
values and comments left out, JSON as Python's json.dumps writes it by default."""

from __future__ import annotations

import hashlib
import json
from typing import Any

from .types import RosField, RosType, load_md, md_types

#: type_interfaces/msg/FieldType ids of the primitives the mapping uses (and bool, byte, char).
FIELD_TYPE_IDS = {
    "nested": 1, "int8": 2, "uint8": 3, "int16": 4, "uint16": 5, "int32": 6, "uint32": 7,
    "int64": 8, "uint64": 9, "float32": 10, "float64": 11, "char": 13, "bool": 15,
    "byte": 16, "string": 17, "bounded_string": 21,
}
ARRAY_OFFSET = 48  # a fixed array T[N] is T's id + 48, capacity N
EMPTY_MEMBER = RosField("structure_needs_at_least_one_member", "uint8")


def _field_type(f: RosField) -> dict[str, Any]:
    if f.is_nested:
        tid = FIELD_TYPE_IDS["nested"]
    elif f.type == "string" and f.string_bound:
        tid = FIELD_TYPE_IDS["bounded_string"]
    else:
        tid = FIELD_TYPE_IDS[f.type]
    return {"type_id": tid + (ARRAY_OFFSET if f.array_size else 0),
            "capacity": f.array_size, "string_capacity": f.string_bound,
            "nested_type_name": f.type if f.is_nested else ""}


def _individual(t: RosType, with_defaults: bool) -> dict[str, Any]:
    fields = []
    for f in t.fields or (EMPTY_MEMBER,):
        entry: dict[str, Any] = {"name": f.name, "type": _field_type(f)}
        if with_defaults:
            entry["default_value"] = ""
        fields.append(entry)
    return {"type_name": t.name, "fields": fields}


def describe(types: list[RosType], with_defaults: bool = True) -> dict[str, Any]:
    """The TypeDescription of types[0] (types[1:]: every type it references), as the dict of
    type_description_interfaces/msg/TypeDescription; without default values: the hashed form."""
    return {"type_description": _individual(types[0], with_defaults),
            "referenced_type_descriptions": [
                _individual(t, with_defaults) for t in sorted(types[1:], key=lambda t: t.name)]}


def hash_types(types: list[RosType]) -> str:
    """RIHS01_<64 hex> of types[0] (types[1:]: every type it references)."""
    text = json.dumps(describe(types, with_defaults=False))
    return "RIHS01_" + hashlib.sha256(text.encode()).hexdigest()


def type_description(md_name: str, md_dirs: list[str] | None = None) -> dict[str, Any]:
    """The ROS 2 TypeDescription (dict) of a topic md's type."""
    return describe(md_types(load_md(md_name, md_dirs)))


def rihs01(md_name: str, md_dirs: list[str] | None = None) -> str:
    """The RIHS01 hash of a topic md's ROS 2 type (cached with its codec)."""
    from .cdr import codec

    return codec(md_name, md_dirs).type_hash
