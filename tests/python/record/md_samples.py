"""Samples of any topic md for the encoding tests: random packed bytes (every integer bit,
float specials, NUL-padded ASCII text) made with the struct module from the md's layout, and
a decoded message of another reader (mcap_ros2's objects, JSON) compared with those bytes
field by field, floats by their bits."""

from __future__ import annotations

import math
import random
import string
import struct
from typing import Any

from links_and_nodes.ros2.names import field_names
from ln_generate.model import Field, Struct

CODES = {"int8_t": "b", "uint8_t": "B", "int16_t": "h", "uint16_t": "H", "int32_t": "i",
         "uint32_t": "I", "int64_t": "q", "uint64_t": "Q", "float": "f", "double": "d",
         "char": "B"}
SPECIALS = (0.0, -0.0, math.inf, -math.inf, math.nan, 1e-300, 0.1, -2.5)
NON_FINITE = {"NaN": math.nan, "Infinity": math.inf, "-Infinity": -math.inf}


def random_sample(layout: Struct, rng: random.Random) -> bytes:
    buf = bytearray(layout.size)
    _fill(layout, buf, 0, rng)
    return bytes(buf)


def _fill(layout: Struct, buf: bytearray, base: int, rng: random.Random) -> None:
    for f in layout.fields:
        at = base + f.offset
        if isinstance(f.type, Struct):
            for i in range(f.count):
                _fill(f.type, buf, at + i * f.type.size, rng)
        elif f.type.kind == "char" and f.kind == "array":
            text = "".join(rng.choice(string.ascii_letters + " .-")
                           for _ in range(rng.randint(0, f.count)))
            buf[at:at + len(text)] = text.encode()
        elif f.type.kind == "char":
            buf[at] = rng.randint(32, 126)
        elif f.type.kind == "float":
            values = [rng.choice(SPECIALS) if rng.random() < 0.3
                      else rng.uniform(-1, 1) * 10 ** rng.randint(-30, 30)
                      for _ in range(f.count)]
            struct.pack_into(f"<{f.count}{CODES[f.type.name]}", buf, at, *values)
        else:
            buf[at:at + f.type.size * f.count] = rng.randbytes(f.type.size * f.count)


def _bits(name: str, value: float) -> bytes:
    return struct.pack("<" + CODES[name], value)


def _scalar(f: Field, value: Any, raw: Any, where: str) -> None:
    name = f.type.name
    if f.type.kind == "float":
        if isinstance(value, str):
            value = NON_FINITE[value]
        assert _bits(name, value) == _bits(name, raw), f"{where}: {value!r} != {raw!r}"
    else:
        assert value == raw and not isinstance(value, float), f"{where}: {value!r} != {raw!r}"


def check(layout: Struct, data: bytes, got: Any, how: str, base: int = 0,
          where: str = "") -> None:
    """Assert that `got` (how="ros2": an mcap_ros2 message object; how="json": a dict of
    json.loads) holds the values of packed sample `data` of `layout`."""
    if how == "json":
        assert list(got) == [f.name for f in layout.fields], f"{where}: {list(got)}"
    names = field_names([f.name for f in layout.fields])
    for f, ros_name in zip(layout.fields, names, strict=True):
        value = got[f.name] if how == "json" else getattr(got, ros_name)
        path = f"{where}.{f.name}" if where else f.name
        at = base + f.offset
        if isinstance(f.type, Struct):
            items = [value] if f.kind == "scalar" else list(value)
            assert len(items) == f.count, path
            for i, item in enumerate(items):
                check(f.type, data, item, how, at + i * f.type.size, f"{path}[{i}]")
            continue
        if f.type.kind == "char" and f.kind == "array":
            text = data[at:at + f.count].split(b"\0", 1)[0].decode()
            assert value == text, f"{path}: {value!r} != {text!r}"
            continue
        raw = struct.unpack_from(f"<{f.count}{CODES[f.type.name]}", data, at)
        if f.type.kind == "char" and how == "json":  # a single char: a one-letter string
            assert value == chr(raw[0]), f"{path}: {value!r}"
            continue
        items = [value] if f.kind == "scalar" else list(value)
        assert len(items) == f.count, f"{path}: {len(items)} values"
        for i, (v, r) in enumerate(zip(items, raw, strict=True)):
            _scalar(f, v, r, f"{path}[{i}]")
