"""Shared by the ROS 2 mapping tests: the mds they cover, random samples in the ln layout
(special floats and ints, char text), the values the generated Python class reads from a
sample, and the two independent CDR decoders (rosbags, mcap-ros2-support)."""

from __future__ import annotations

import dataclasses
import math
import struct
from pathlib import Path
from typing import Any

import numpy as np
from buildtree import missing_test_tool

from links_and_nodes.ros2.names import field_names
from ln_generate import MdError, MdRegistry, Struct, default_md_dirs
from ln_generate.emit_python import emit

REPO = Path(__file__).resolve().parents[3]
TEST_MDS = Path(__file__).resolve().parent / "md"
REAL_MDS = REPO.parent / "shared" / "real_ln" / "md"
SEPARATOR = "=" * 80 + "\n"


def md_names(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*")
                  if p.is_file() and p.name != "SConscript")


def topic_mds(root: Path) -> list[str]:
    """The message mds below `root` without dynamic fields (those a topic sample can hold)."""
    out = []
    for name in md_names(root):
        try:
            md = MdRegistry(default_md_dirs([str(root)])).load(name)
        except MdError:
            continue
        if md.kind == "message" and not md.struct.has_dynamic:
            out.append(name)
    return out


def real_topic_mds() -> list[tuple[str, str]]:
    """(md directory, md name) of the real mds that fit topics (read in place)."""
    if not REAL_MDS.is_dir():
        return []
    return [(str(d), n) for d in sorted(REAL_MDS.iterdir()) if d.is_dir() for n in topic_mds(d)]


def ln_class(md_name: str, md_dirs: list[str]) -> Any:
    """The Python class ln_generate emits for the md (as md_loader.message_class builds it)."""
    md = MdRegistry(default_md_dirs(md_dirs)).load(md_name)
    source = emit([md], Path(f"<md {md_name}>"), "runtime")
    namespace: dict[str, Any] = {"__name__": "ros2_test_md"}
    exec(compile(source, f"<md {md_name}>", "exec"), namespace)
    return namespace["MESSAGES"][md_name]


# ---- random samples -----------------------------------------------------------------------

_F64 = [math.nan, -math.nan, math.inf, -math.inf, -0.0, 0.0, 1e308, -5e-324]
_NAN_PAYLOADS = {8: [b"\x01\x00\x00\x00\x00\x00\xf4\x7f", b"\xff\xff\xff\xff\xff\xff\xff\xff"],
                 4: [b"\x01\x00\xa0\x7f", b"\xff\xff\xff\xff"]}
_TEXT = "abcxyzABC019 _-.:éß€"


def _special(rng: np.random.Generator, prim: Any, payloads: bool) -> bytes:
    if prim.kind == "float":
        fmt = "<d" if prim.size == 8 else "<f"
        choices = [struct.pack(fmt, v) for v in _F64 if prim.size == 8 or abs(v) < 1e38]
        if payloads:
            choices += _NAN_PAYLOADS[prim.size]
        return choices[rng.integers(len(choices))]
    bits = prim.size * 8
    if prim.kind == "uint":
        values = [0, (1 << bits) - 1]
    else:
        values = [-(1 << (bits - 1)), (1 << (bits - 1)) - 1, -1]
    return int(values[rng.integers(len(values))]).to_bytes(
        prim.size, "little", signed=prim.kind != "uint")


def _text(rng: np.random.Generator, capacity: int) -> bytes:
    target = int(rng.integers(0, capacity + 1))
    out = b""
    while True:
        c = _TEXT[rng.integers(len(_TEXT))].encode()
        if len(out) + len(c) > target:
            return out
        out += c


def fill(struct_: Struct, rng: np.random.Generator, payloads: bool = True) -> bytes:
    """A random sample: random bytes, ~30 % of the numbers special (NaN, inf, -0.0, limits;
    NaNs with payloads if `payloads`), every char[N] a text of 0..N bytes, zero padded."""
    buf = bytearray(rng.bytes(struct_.size))
    _fill(struct_, 0, buf, rng, payloads)
    return bytes(buf)


def _fill(s: Struct, base: int, buf: bytearray, rng: np.random.Generator,
          payloads: bool) -> None:
    for f in s.fields:
        at = base + f.offset
        if isinstance(f.type, Struct):
            for i in range(f.count):
                _fill(f.type, at + i * f.type.size, buf, rng, payloads)
        elif f.type.kind == "char" and f.kind == "array":
            buf[at:at + f.count] = _text(rng, f.count).ljust(f.count, b"\0")
        elif f.type.kind == "float" and not payloads:
            for i in range(f.count):  # no NaN payloads: Python floats would change them
                p = at + i * f.type.size
                if rng.random() < 0.3:
                    buf[p:p + f.type.size] = _special(rng, f.type, False)
                else:
                    fmt = "<d" if f.type.size == 8 else "<f"
                    buf[p:p + f.type.size] = struct.pack(fmt, float(rng.normal() * 1e3))
        elif f.type.kind != "char":
            for i in range(f.count):
                if rng.random() < 0.3:
                    p = at + i * f.type.size
                    buf[p:p + f.type.size] = _special(rng, f.type, payloads)


# ---- values -------------------------------------------------------------------------------

def ln_values(d: dict[str, Any], s: Struct) -> dict[str, Any]:
    """The generated class's to_dict() keyed by ROS field names; a char as its byte."""
    out = {}
    for f, name in zip(s.fields, field_names([f.name for f in s.fields]), strict=True):
        v = d[f.name]
        if isinstance(f.type, Struct):
            v = [ln_values(x, f.type) for x in v] if f.kind == "array" else ln_values(v, f.type)
        elif f.type.kind == "char" and f.kind != "array":
            v = (v.encode("utf-8", "surrogateescape") or b"\0")[0]
        out[name] = v
    return out


def plain(x: Any) -> Any:
    """A decoded ROS message as dicts, lists and numbers."""
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, (bytes, bytearray)):
        return list(x)
    if isinstance(x, (list, tuple)):
        return [plain(i) for i in x]
    if dataclasses.is_dataclass(x):
        return {f.name: plain(getattr(x, f.name)) for f in dataclasses.fields(x)
                if not f.name.startswith("__")}  # rosbags: __msgtype__ is not a field
    if hasattr(x, "__slots__") and not isinstance(x, (int, float, str)):
        return {s: plain(getattr(x, s)) for s in x.__slots__}
    return x


def differences(a: Any, b: Any, path: str = "") -> list[str]:
    """Where `a` and `b` differ (see same()), for assertion messages."""
    if isinstance(a, dict) and isinstance(b, dict) and a.keys() != b.keys():
        return [f"{path}: keys {sorted(a)} != {sorted(b)}"]
    if isinstance(a, dict) and isinstance(b, dict):
        return [d for k in a for d in differences(a[k], b[k], f"{path}.{k}")]
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        return [d for i, (x, y) in enumerate(zip(a, b, strict=True))
                for d in differences(x, y, f"{path}[{i}]")]
    return [] if same(a, b) else [f"{path}: {a!r} ({type(a).__name__}) != {b!r} "
                                  f"({type(b).__name__})"]


def same(a: Any, b: Any) -> bool:
    """Equal values; NaN equals NaN, 0.0 differs from -0.0."""
    if isinstance(a, float) or isinstance(b, float):
        if not isinstance(a, (int, float)) or not isinstance(b, (int, float)):
            return False
        if math.isnan(a) or math.isnan(b):
            return math.isnan(a) and math.isnan(b)
        return a == b and math.copysign(1, a) == math.copysign(1, b)
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    return type(a) is type(b) and a == b


# ---- independent decoders -----------------------------------------------------------------

def rosbags_store(schema: str, type_name: str) -> Any:
    """A rosbags type store with the types of a ros2msg schema registered from its text."""
    try:
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore
    except ImportError:
        missing_test_tool("the PyPI package rosbags (requirements-dev.txt)")

    store = get_typestore(Stores.EMPTY)
    parts = schema.split(SEPARATOR)
    types = dict(get_types_from_msg(parts[0], type_name))
    for part in parts[1:]:
        first, _, body = part.partition("\n")
        assert first.startswith("MSG: "), first
        types.update(get_types_from_msg(body, first.removeprefix("MSG: ")))
    store.register(types)
    return store


def mcap_decoder(schema: str, type_name: str) -> Any:
    """mcap-ros2-support's CDR decoder built from the schema, as a viewer would build it."""
    try:
        from mcap.records import Schema
        from mcap_ros2.decoder import DecoderFactory
    except ImportError:
        missing_test_tool("the PyPI package mcap-ros2-support (requirements-dev.txt)")

    decoder = DecoderFactory().decoder_for(
        "cdr", Schema(id=1, name=type_name, encoding="ros2msg", data=schema.encode()))
    assert decoder is not None
    return decoder
