"""The typed model of message definitions: primitives, fields, structs, mds.

A Struct is one packed little-endian record (a plain message, or one section of a
service/event). Offsets and sizes are computed once, here, and every emitter uses
them, so C, C++ and Python cannot disagree about the layout.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

from .diagnostics import Location

FieldKind = Literal["scalar", "array", "dynamic"]
MdKind = Literal["message", "service", "event"]

#: Size of the length prefix and of the pointer that make up a dynamic field in
#: the in-memory struct (`uint32_t NAME_len; T* NAME;`). 64-bit targets only.
DYN_LEN_SIZE = 4
POINTER_SIZE = 8

#: Largest struct the generator accepts (the topic limit is far lower).
MAX_STRUCT_SIZE = 1 << 30


@dataclass(frozen=True)
class Primitive:
    name: str  # canonical name, as in signatures: "double", "uint32_t", ...
    size: int
    c_type: str
    ctypes_type: str  # attribute of the ctypes module
    numpy_dtype: str  # explicit little-endian numpy dtype string
    kind: Literal["int", "uint", "float", "char"]


def _prims() -> dict[str, Primitive]:
    table = [
        Primitive("char", 1, "char", "c_char", "S1", "char"),
        Primitive("int8_t", 1, "int8_t", "c_int8", "i1", "int"),
        Primitive("uint8_t", 1, "uint8_t", "c_uint8", "u1", "uint"),
        Primitive("int16_t", 2, "int16_t", "c_int16", "<i2", "int"),
        Primitive("uint16_t", 2, "uint16_t", "c_uint16", "<u2", "uint"),
        Primitive("int32_t", 4, "int32_t", "c_int32", "<i4", "int"),
        Primitive("uint32_t", 4, "uint32_t", "c_uint32", "<u4", "uint"),
        Primitive("int64_t", 8, "int64_t", "c_int64", "<i8", "int"),
        Primitive("uint64_t", 8, "uint64_t", "c_uint64", "<u8", "uint"),
        Primitive("float", 4, "float", "c_float", "<f4", "float"),
        Primitive("double", 8, "double", "c_double", "<f8", "float"),
    ]
    return {p.name: p for p in table}


PRIMITIVES: dict[str, Primitive] = _prims()

#: Type names accepted in definitions, aliases included, mapped to the primitive.
TYPE_NAMES: dict[str, Primitive] = {
    **PRIMITIVES,
    "float32_t": PRIMITIVES["float"],
    "float64_t": PRIMITIVES["double"],
    "int": PRIMITIVES["int32_t"],
    "short": PRIMITIVES["int16_t"],
}

UINT32 = PRIMITIVES["uint32_t"]


@dataclass
class Field:
    name: str
    type: Primitive | Struct
    kind: FieldKind
    count: int  # elements of a static array; 1 for scalars, 0 for dynamic fields
    loc: Location
    offset: int = 0
    doc: str = ""  # the trailing comment of the field's line

    @property
    def size(self) -> int:
        """Bytes this field occupies in the struct."""
        if self.kind == "dynamic":
            return DYN_LEN_SIZE + POINTER_SIZE
        return self.type.size * self.count

    @property
    def len_name(self) -> str:
        return f"{self.name}_len"

    @property
    def pointer_offset(self) -> int:
        return self.offset + DYN_LEN_SIZE

    @property
    def is_nested(self) -> bool:
        return isinstance(self.type, Struct)


@dataclass
class Struct:
    md_name: str  # md this record belongs to
    section: str | None  # None for a plain message, else "request", "response", ...
    fields: list[Field] = field(default_factory=list)
    size: int = 0

    def layout(self) -> None:
        offset = 0
        for f in self.fields:
            f.offset = offset
            offset += f.size
        self.size = offset

    @property
    def has_dynamic(self) -> bool:
        return any(
            f.kind == "dynamic" or (isinstance(f.type, Struct) and f.type.has_dynamic)
            for f in self.fields
        )

    def nested_structs(self) -> list[Struct]:
        """Structs used by this one, dependencies first, each once."""
        seen: dict[int, Struct] = {}
        for f in self.fields:
            if isinstance(f.type, Struct):
                for s in [*f.type.nested_structs(), f.type]:
                    seen.setdefault(id(s), s)
        return list(seen.values())


@dataclass
class MessageDef:
    name: str
    kind: MdKind
    path: Path
    sections: dict[str, Struct]  # "" for a plain message, else section name -> struct
    doc: str = ""
    imports: dict[str, MessageDef] = field(default_factory=dict)  # local alias -> md
    signature: str = ""
    layout_hash: int = 0

    @property
    def struct(self) -> Struct:
        """The record of a plain message (not valid for services/events)."""
        assert self.kind == "message"
        return self.sections[""]

    def dependencies(self) -> list[MessageDef]:
        """Imported mds, transitively, dependencies first, each once."""
        out: dict[str, MessageDef] = {}
        for md in self.imports.values():
            for dep in [*md.dependencies(), md]:
                out.setdefault(dep.name, dep)
        return list(out.values())


#: Section names of each kind of md, in declaration order.
SECTIONS: dict[str, tuple[str, ...]] = {
    "message": ("",),
    "service": ("request", "response"),
    "event": ("connect", "call"),
}
