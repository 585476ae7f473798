"""Signature strings and 64-bit layout hashes of the model.

The hash covers exactly what decides the bytes and their meaning: for every field
in order its name, its kind (scalar, static array, dynamic), its element count and
its type, where a nested md contributes its own fields recursively (not its name).
Comments, whitespace, local define aliases and md file names do not change it.
"""

from __future__ import annotations

import hashlib

from .model import MessageDef, Primitive, Struct

LAYOUT_VERSION = 1
_KIND_TAG = {"scalar": "s", "array": "a", "dynamic": "d"}


def canonical(struct: Struct) -> str:
    """An injective text form of a struct's flattened layout (the hash input)."""
    parts = []
    for f in struct.fields:
        t = f.type.name if isinstance(f.type, Primitive) else canonical(f.type)
        parts.append(f"{f.name}:{t}:{_KIND_TAG[f.kind]}{f.count}")
    return "{" + ";".join(parts) + "}"


def md_canonical(md: MessageDef) -> str:
    sections = "|".join(f"{name}={canonical(s)}" for name, s in md.sections.items())
    return f"ln-layout-{LAYOUT_VERSION}:{md.kind}:{sections}"


def layout_hash(md: MessageDef) -> int:
    """First 8 bytes (little-endian) of SHA-256 over the canonical layout."""
    digest = hashlib.sha256(md_canonical(md).encode()).digest()
    return int.from_bytes(digest[:8], "little")


def struct_signature(struct: Struct) -> str:
    """LN-style `TYPE SIZE COUNT` items; nested records in `[...]`; `*` marks dynamic."""
    items = []
    for f in struct.fields:
        if isinstance(f.type, Primitive):
            elem, size = f.type.name, f.type.size
        else:
            elem, size = f"[{struct_signature(f.type)}]", f.type.size
        if f.kind == "dynamic":
            items.append(f"uint32_t 4 1,{elem}* {size} 1")
        else:
            items.append(f"{elem} {size} {f.count}")
    return ",".join(items)


def md_signature(md: MessageDef) -> str:
    """Sections joined by `|` (request|response, connect|call)."""
    return "|".join(struct_signature(s) for s in md.sections.values())
