"""The numeric fields of a message definition as the scope plots them: one path per
number ("position[3]", "pose.x", "links[1].mass[0]") with its byte offset and struct code,
so that a sample's values are read without decoding the whole sample."""

from __future__ import annotations

import struct
from dataclasses import dataclass

from ln_generate.model import Struct

from ....tools.introspection.values import _CODES

MAX_FIELDS = 4096  # paths listed per md (arrays beyond are cut)


@dataclass(frozen=True)
class NumericField:
    path: str
    offset: int
    code: str  # struct code, little-endian
    type: str  # md type name


def numeric_fields(layout: Struct, prefix: str = "", base: int = 0,
                   out: list[NumericField] | None = None) -> list[NumericField]:
    out = [] if out is None else out
    for f in layout.fields:
        if len(out) >= MAX_FIELDS or f.kind == "dynamic":
            continue
        name = f"{prefix}{f.name}"
        offset = base + f.offset
        if isinstance(f.type, Struct):
            if f.kind == "scalar":
                numeric_fields(f.type, name + ".", offset, out)
            else:
                for i in range(f.count):
                    numeric_fields(f.type, f"{name}[{i}].", offset + i * f.type.size, out)
            continue
        code = _CODES.get(f.type.name)
        if code is None:  # char
            continue
        if f.kind == "scalar":
            out.append(NumericField(name, offset, code, f.type.name))
        else:
            out.extend(NumericField(f"{name}[{i}]", offset + i * f.type.size, code,
                                    f.type.name) for i in range(f.count))
    return out


class Extractor:
    """Reads the chosen fields out of raw samples."""

    def __init__(self, chosen: list[NumericField]) -> None:
        self.fields = chosen
        self._unpack = [struct.Struct("<" + f.code).unpack_from for f in chosen]
        self._offsets = [f.offset for f in chosen]

    def __call__(self, data: bytes) -> list[float]:
        return [float(u(data, o)[0]) for u, o in zip(self._unpack, self._offsets, strict=True)]
