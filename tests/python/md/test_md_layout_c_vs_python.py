"""C and Python agree on the bytes of every message definition in the tree.

For every md under message_definitions/ and tests/fixtures/md/valid*/ the C header and the
Python module are generated and the headers are compiled with cffi next to probe
functions written from the model: sizeof/offsetof of every struct and member, and a
fill and a read function that copy every leaf to or from two value arrays. Random
values then cross the language boundary in both directions, checked leaf by leaf.
"""

from __future__ import annotations

import ctypes
import math
import os
import random
import struct as pystruct
import subprocess
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest
from cffi import FFI
from gen_modules import load_module

import ln_generate
from ln_generate import (
    MdRegistry,
    MessageDef,
    Primitive,
    Struct,
    default_md_dirs,
    emit_c,
    emit_python,
)
from ln_generate.lookup import check_name
from ln_generate.model import UINT32
from ln_generate.names import c_name

REPO = Path(__file__).resolve().parents[3]
TRIALS = 3  # random rounds per struct and direction

#: Member names of the combined struct of a service or event (part of the contract).
COMBINED_MEMBER = {"request": "req", "response": "resp", "connect": "connect", "call": "call"}
#: Independent of the generator's own tables: struct format and range of each primitive.
PRIM_FORMAT = {
    "char": "B", "int8_t": "b", "uint8_t": "B", "int16_t": "<h", "uint16_t": "<H",
    "int32_t": "<i", "uint32_t": "<I", "int64_t": "<q", "uint64_t": "<Q",
    "float": "<f", "double": "<d",
}
NUMPY_DTYPE = {
    "int8_t": "i1", "uint8_t": "u1", "int16_t": "<i2", "uint16_t": "<u2",
    "int32_t": "<i4", "uint32_t": "<u4", "int64_t": "<i8", "uint64_t": "<u8",
    "float": "<f4", "double": "<f8",
}
BUILD_FILES = {"SConscript", "SConstruct"}
TEXT_ALPHABET = "abcXYZ019 _-.:/é€中\udcff"  # \udcff: a raw 0xff byte via surrogateescape


def md_dirs() -> dict[str, Path]:
    dirs = {"message_definitions": REPO / "message_definitions"}
    for d in sorted((REPO / "tests" / "fixtures" / "md").glob("valid*")):
        if d.is_dir():
            dirs[f"tests/fixtures/md/{d.name}"] = d
    return dirs


def md_names(root: Path) -> list[str]:
    """Every file below `root` whose relative path is a valid md name (build files aside)."""
    names = (p.relative_to(root).as_posix() for p in root.rglob("*")
             if p.is_file() and p.name not in BUILD_FILES)
    return sorted(n for n in names if check_name(n) is None)


DIRS = md_dirs()
CASES = [(tag, name) for tag, root in DIRS.items() for name in md_names(root)]


def is_float(p: Primitive) -> bool:
    return p.name in ("float", "double")


def is_signed(p: Primitive) -> bool:
    return p.name.startswith("int")


@dataclass(frozen=True)
class Leaf:
    expr: str  # C member path below the struct, e.g. "m.many[2].b[1]"
    prim: Primitive | None  # None for the pointer of a dynamic field
    offset: int  # byte offset in the struct, from the model


def leaves(s: Struct, prefix: str = "", base: int = 0) -> Iterator[Leaf]:
    """Every scalar in `s`, nested structs and array elements expanded, in memory order."""
    for f in s.fields:
        if f.kind == "dynamic":
            yield Leaf(prefix + f.len_name, UINT32, base + f.offset)
            yield Leaf(prefix + f.name, None, base + f.pointer_offset)
            continue
        for i in [None] if f.kind == "scalar" else range(f.count):
            expr = prefix + f.name + ("" if i is None else f"[{i}]")
            offset = base + f.offset + (i or 0) * f.type.size
            if isinstance(f.type, Struct):
                yield from leaves(f.type, expr + ".", offset)
            else:
                yield Leaf(expr, f.type, offset)


def value_leaves(s: Struct) -> tuple[list[Leaf], list[Leaf]]:
    """(integer-valued leaves, float-valued leaves), each in C array order."""
    ints, floats = [], []
    for leaf in leaves(s):
        if leaf.prim is not None:
            (floats if is_float(leaf.prim) else ints).append(leaf)
    return ints, floats


# ---------------------------------------------------------------- C probe source


@dataclass
class CStruct:
    ctype: str
    md: MessageDef
    struct: Struct | None  # None for the combined struct of a service/event
    members: list[tuple[str, int]]  # C member -> offset expected from the model
    size: int  # sizeof expected in C (a 1-byte placeholder for empty sections)


def c_structs(md: MessageDef) -> list[CStruct]:
    out = []
    for s in md.sections.values():
        members: list[tuple[str, int]] = []
        for f in s.fields:
            if f.kind == "dynamic":
                members += [(f.len_name, f.offset), (f.name, f.pointer_offset)]
            else:
                members.append((f.name, f.offset))
        if not s.fields:
            members = [("_ln_empty", 0)]
        out.append(CStruct(emit_c.struct_c_name(s), md, s, members, s.size or 1))
    if md.kind != "message":
        members, offset = [], 0
        for name, s in md.sections.items():
            members.append((COMBINED_MEMBER[name], offset))
            offset += s.size or 1
        out.append(CStruct(f"{c_name(md.name)}_t", md, None, members, offset))
    return out


def c_int(prim: Primitive, value: int) -> int:
    """`value` as the int64_t that converts to it in C (two's complement wrap)."""
    bits = prim.size * 8
    return value - (1 << bits) if not is_signed(prim) and value >= 1 << (bits - 1) else value


def from_c_int(prim: Primitive, value: int) -> int:
    """Undo the sign extension of an unsigned (or char) leaf read into an int64_t."""
    return value if is_signed(prim) else value & ((1 << (prim.size * 8)) - 1)


def fill_read_source(cs: CStruct) -> list[str]:
    assert cs.struct is not None
    ints, floats = value_leaves(cs.struct)
    fill = [f"void fill_{cs.ctype}(void *p, const int64_t *iv, const double *fv) {{",
            f"    {cs.ctype} *s = p;", "    (void)s; (void)iv; (void)fv;"]
    read = [f"void read_{cs.ctype}(const void *p, int64_t *iv, double *fv) {{",
            f"    const {cs.ctype} *s = p;", "    (void)s; (void)iv; (void)fv;"]
    for i, leaf in enumerate(ints):
        assert leaf.prim is not None
        fill.append(f"    s->{leaf.expr} = ({leaf.prim.c_type})iv[{i}];")
        read.append(f"    iv[{i}] = (int64_t)s->{leaf.expr};")
    for i, leaf in enumerate(floats):
        assert leaf.prim is not None
        fill.append(f"    s->{leaf.expr} = ({leaf.prim.c_type})fv[{i}];")
        read.append(f"    fv[{i}] = (double)s->{leaf.expr};")
    fill += [f"    s->{leaf.expr} = NULL;" for leaf in leaves(cs.struct) if leaf.prim is None]
    return [*fill, "}", *read, "}"]


def probe_source(mds: list[MessageDef], headers: list[str]) -> tuple[str, str]:
    """(cdef, C source) of the probe functions for `mds`; their headers are `headers`."""
    cdef: list[str] = []
    src = ["#include <stddef.h>", "#include <stdint.h>",
           *(f'#include "{h}"' for h in headers), ""]
    for i, md in enumerate(mds):
        macro = c_name(md.name).upper()
        for fn, rtype, expr in [
            ("md_name", "const char *", f"{macro}_MD_NAME"),
            ("signature", "const char *", f"{macro}_SIGNATURE"),
            ("layout_hash", "uint64_t", f"{macro}_LAYOUT_HASH"),
            ("marker", "uint64_t", f"LN_MD_{macro}"),
            *((f"size_{sec or 'message'}", "size_t",
               f"{macro}{'_' + sec.upper() if sec else ''}_SIZE") for sec in md.sections),
        ]:
            cdef.append(f"{rtype} {fn}_{i}(void);")
            src.append(f"{rtype} {fn}_{i}(void) {{ return {expr}; }}")
        for cs in c_structs(md):
            cdef.append(f"size_t sizeof_{cs.ctype}(void);")
            src.append(f"size_t sizeof_{cs.ctype}(void) {{ return sizeof({cs.ctype}); }}")
            for member, _ in cs.members:
                fn = f"offsetof_{cs.ctype}_{member}"
                cdef.append(f"size_t {fn}(void);")
                src.append(f"size_t {fn}(void) {{ return offsetof({cs.ctype}, {member}); }}")
            if cs.struct is not None:
                cdef.append(f"void fill_{cs.ctype}(void *, const int64_t *, const double *);")
                cdef.append(f"void read_{cs.ctype}(const void *, int64_t *, double *);")
                src += fill_read_source(cs)
    names = [line.split("(")[0].split()[-1] for line in cdef]
    assert len(names) == len(set(names)), "probe function names clash"
    return "\n".join(cdef), "\n".join(src) + "\n"


# ---------------------------------------------------------------- build per md dir


@dataclass
class Built:
    tag: str
    mds: dict[str, MessageDef]
    index: dict[str, int]  # md name -> index in the probe function names
    lib: Any
    ffi: FFI
    py: dict[str, ModuleType]  # md name -> generated Python module
    gen_dir: Path


def build(tag: str, root: Path, tmp: Path) -> Built:
    registry = MdRegistry(default_md_dirs([str(root)]))
    names = md_names(root)
    mds = {n: registry.load(n) for n in names}
    gen = tmp / "gen"
    gen.mkdir()
    version = ln_generate.__version__
    uniq = f"{c_name(tag.replace('.', '_').replace('-', '_'))}_{os.getpid()}"
    headers, py = [], {}
    for name, md in mds.items():
        stem = c_name(name)
        header = gen / f"{stem}.h"
        header.write_text(emit_c.emit([md], header, version))
        headers.append(header.name)
        module = gen / f"{stem}.py"
        module.write_text(emit_python.emit([md], module, version))
        py[name] = load_module(f"lntest_md_{uniq}_{stem}", module)
    cdef, source = probe_source(list(mds.values()), headers)
    ffi = FFI()
    ffi.cdef(cdef)
    modname = f"_lntest_layout_{uniq}"
    ffi.set_source(modname, source, include_dirs=[str(gen)])
    so = ffi.compile(tmpdir=str(tmp / "build"), verbose=False)
    lib = load_module(modname, Path(so)).lib
    return Built(tag, mds, {n: i for i, n in enumerate(mds)}, lib, ffi, py, gen)


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> Any:
    """Compiles each md dir once per module (and per xdist worker), on first use."""
    cache: dict[str, Built | BaseException] = {}

    def get(tag: str) -> Built:
        if tag not in cache:
            tmp = tmp_path_factory.mktemp(f"layout_{c_name(tag).replace('.', '_')}")
            try:
                cache[tag] = build(tag, DIRS[tag], tmp)
            except Exception as e:  # report a failed build once per test, not rebuild it
                cache[tag] = e
        result = cache[tag]
        if isinstance(result, BaseException):
            raise result
        return result

    return get


def py_class(b: Built, md_name: str, ctype: str) -> type[ctypes.Structure]:
    return getattr(b.py[md_name], ctype)


# ---------------------------------------------------------------- value handling


def random_int(rng: random.Random, prim: Primitive) -> int:
    bits = prim.size * 8
    if is_signed(prim):
        lo, hi = -(1 << (bits - 1)), (1 << (bits - 1)) - 1
    else:
        lo, hi = 0, (1 << bits) - 1
    if rng.random() < 0.2:
        return rng.choice([lo, hi, 0, 1, lo + 1, hi - 1])
    return rng.randint(lo, hi)


def random_float(rng: random.Random, prim: Primitive) -> float:
    """Any non-NaN value of the type (infinities and subnormals included)."""
    fmt = PRIM_FORMAT[prim.name]
    while True:
        if rng.random() < 0.5:
            raw = rng.getrandbits(prim.size * 8).to_bytes(prim.size, "little")
            v = pystruct.unpack(fmt, raw)[0]
        else:  # everyday magnitudes, rounded to the type
            v = pystruct.unpack(fmt, pystruct.pack(fmt, rng.uniform(-1e4, 1e4)))[0]
        if not math.isnan(v):
            return v


def random_leaf(rng: random.Random, prim: Primitive) -> int | float:
    return random_float(rng, prim) if is_float(prim) else random_int(rng, prim)


def random_text(rng: random.Random, max_bytes: int) -> str:
    """A str whose UTF-8 (surrogateescape) form has at most `max_bytes` bytes."""
    target = rng.randint(0, max_bytes)
    text = ""
    while True:
        ch = rng.choice(TEXT_ALPHABET)
        if len((text + ch).encode("utf-8", "surrogateescape")) > target:
            return text
        text += ch


def same(a: int | float, b: int | float) -> bool:
    """Equal, and for floats bit for bit (so -0.0 differs from 0.0)."""
    if isinstance(a, float) or isinstance(b, float):
        return pystruct.pack("<d", a) == pystruct.pack("<d", b)
    return a == b


def c_fill_values(s: Struct, rng: random.Random, prefix: str = "") -> dict[str, int | float]:
    """Random leaf values for the C side: char arrays hold bytes 1..255 then NUL padding."""
    out: dict[str, int | float] = {}
    for f in s.fields:
        p = prefix + f.name
        if f.kind == "dynamic":
            out[prefix + f.len_name] = random_int(rng, UINT32)
        elif isinstance(f.type, Struct):
            for i in [None] if f.kind == "scalar" else range(f.count):
                out |= c_fill_values(f.type, rng, p + ("" if i is None else f"[{i}]") + ".")
        elif f.type.name == "char" and f.kind == "array":
            n = rng.randint(0, f.count)
            data = bytes(rng.randint(1, 255) for _ in range(n)).ljust(f.count, b"\0")
            out |= {f"{p}[{i}]": data[i] for i in range(f.count)}
        elif f.type.name == "char":
            out[p] = rng.randint(0, 255)
        elif f.kind == "scalar":
            out[p] = random_leaf(rng, f.type)
        else:
            out |= {f"{p}[{i}]": random_leaf(rng, f.type) for i in range(f.count)}
    return out


def py_read(obj: Any, s: Struct, prefix: str = "") -> dict[str, int | float]:
    """Every leaf of `obj` read through the generated class's public accessors."""
    out: dict[str, int | float] = {}
    for f in s.fields:
        p = prefix + f.name
        if f.kind == "dynamic":
            out[prefix + f.len_name] = getattr(obj, f.len_name)
            continue
        value = getattr(obj, f.name)
        if isinstance(f.type, Struct):
            if f.kind == "scalar":
                out |= py_read(value, f.type, p + ".")
            else:
                assert len(value) == f.count
                for i in range(f.count):
                    out |= py_read(value[i], f.type, f"{p}[{i}].")
        elif f.type.name == "char" and f.kind == "array":
            assert isinstance(value, str), f"{p}: char array should read as str"
            data = value.encode("utf-8", "surrogateescape")
            assert len(data) <= f.count
            data = data.ljust(f.count, b"\0")
            out |= {f"{p}[{i}]": data[i] for i in range(f.count)}
        elif f.type.name == "char":
            assert isinstance(value, str) and len(value) <= 1, f"{p}: char should read as str"
            data = value.encode("utf-8", "surrogateescape")
            out[p] = data[0] if data else 0
        elif f.kind == "scalar":
            assert isinstance(value, float if is_float(f.type) else int), p
            out[p] = value
        else:
            assert isinstance(value, np.ndarray), f"{p}: numeric array should read as numpy"
            assert value.dtype == np.dtype(NUMPY_DTYPE[f.type.name]) and value.shape == (f.count,)
            out |= {f"{p}[{i}]": value[i].item() for i in range(f.count)}
    return out


def py_write(obj: Any, s: Struct, rng: random.Random, prefix: str = "") -> dict[str, int | float]:
    """Set every leaf of `obj` through the public accessors; returns the values set."""
    out: dict[str, int | float] = {}
    for f in s.fields:
        p = prefix + f.name
        if f.kind == "dynamic":
            n = rng.randint(0, 4)
            value: Any
            if isinstance(f.type, Struct):
                value = [{} for _ in range(n)]
            elif f.type.name == "char":
                value = random_text(rng, n)
                n = len(value.encode("utf-8", "surrogateescape"))
            else:
                value = [random_leaf(rng, f.type) for _ in range(n)]
            setattr(obj, f.name, value)
            out[prefix + f.len_name] = n
            back = getattr(obj, f.name)
            if isinstance(f.type, Struct):
                assert len(back) == n, p
            elif f.type.name == "char":
                assert back == value, p
            else:
                assert all(same(a, b) for a, b in zip(back.tolist(), value, strict=True)), p
        elif isinstance(f.type, Struct):
            if f.kind == "scalar":
                out |= py_write(getattr(obj, f.name), f.type, rng, p + ".")
            else:
                items = getattr(obj, f.name)
                for i in range(f.count):
                    out |= py_write(items[i], f.type, rng, f"{p}[{i}].")
        elif f.type.name == "char" and f.kind == "array":
            text = random_text(rng, f.count)
            setattr(obj, f.name, text)
            data = text.encode("utf-8", "surrogateescape").ljust(f.count, b"\0")
            out |= {f"{p}[{i}]": data[i] for i in range(f.count)}
        elif f.type.name == "char":
            out[p] = rng.randint(0, 255)
            setattr(obj, f.name, bytes([int(out[p])]))
        elif f.kind == "scalar":
            out[p] = random_leaf(rng, f.type)
            setattr(obj, f.name, out[p])
        else:
            values = [random_leaf(rng, f.type) for _ in range(f.count)]
            if rng.random() < 0.5:
                getattr(obj, f.name)[:] = values  # through the numpy view
            else:
                setattr(obj, f.name, values)  # through the property setter
            out |= {f"{p}[{i}]": v for i, v in enumerate(values)}
    return out


def model_read(data: bytes, s: Struct) -> dict[str, int | float]:
    """Every value leaf unpacked from raw bytes at the offsets of the model."""
    out = {}
    for leaf in leaves(s):
        if leaf.prim is not None:
            out[leaf.expr] = pystruct.unpack_from(PRIM_FORMAT[leaf.prim.name], data, leaf.offset)[0]
    return out


def assert_leaves_equal(got: dict[str, int | float], want: dict[str, int | float], what: str):
    assert got.keys() == want.keys(), what
    bad = [(k, got[k], want[k]) for k in want if not same(got[k], want[k])]
    assert not bad, f"{what}: {len(bad)} leaves differ, first: {bad[:5]}"


# ---------------------------------------------------------------- tests


def case_id(case: tuple[str, str]) -> str:
    return f"{case[0]}:{case[1]}"


def test_every_md_dir_has_mds() -> None:
    for tag, root in DIRS.items():
        assert md_names(root), f"no message definitions found in {tag}"
    assert any(tag.startswith("tests/fixtures/md/valid") for tag in DIRS)


@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_sizes_and_offsets(built: Any, case: tuple[str, str]) -> None:
    tag, name = case
    b = built(tag)
    md = b.mds[name]
    for cs in c_structs(md):
        cls = py_class(b, name, cs.ctype)
        # A mirror of the generated _fields_: the generated class has replaced the raw
        # descriptors of array, char and dynamic fields with properties.
        mirror = type("Mirror", (ctypes.LittleEndianStructure,),
                      {"_pack_": cls._pack_, "_fields_": cls._fields_})
        c_size = getattr(b.lib, f"sizeof_{cs.ctype}")()
        assert c_size == cs.size == ctypes.sizeof(cls) == ctypes.sizeof(mirror), cs.ctype
        assert [f[0] for f in cls._fields_] == [m for m, _ in cs.members], cs.ctype
        for member, offset in cs.members:
            c_off = getattr(b.lib, f"offsetof_{cs.ctype}_{member}")()
            py_off = getattr(mirror, member).offset
            assert c_off == py_off == offset, f"{cs.ctype}.{member}"
        if cs.struct is not None:
            assert cls.SIZE == cs.struct.size
            assert cls.MD_NAME == name
            specs = [(f.name, f.kind, f.count) for f in cs.struct.fields]
            assert [(n, k, c) for n, k, _, c in cls._ln_specs_] == specs


@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_constants_match(built: Any, case: tuple[str, str]) -> None:
    tag, name = case
    b = built(tag)
    md = b.mds[name]
    i = b.index[name]
    cls = getattr(b.py[name], f"{c_name(name)}_t")
    signature = b.ffi.string(getattr(b.lib, f"signature_{i}")()).decode()
    assert b.ffi.string(getattr(b.lib, f"md_name_{i}")()).decode() == name == cls.MD_NAME
    assert signature == md.signature == cls.SIGNATURE
    assert getattr(b.lib, f"layout_hash_{i}")() == md.layout_hash == cls.LAYOUT_HASH
    assert getattr(b.lib, f"marker_{i}")() == md.layout_hash
    assert b.py[name].MESSAGES[name] is cls
    for sec, s in md.sections.items():
        assert getattr(b.lib, f"size_{sec or 'message'}_{i}")() == s.size


@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_c_to_python(built: Any, case: tuple[str, str]) -> None:
    tag, name = case
    b = built(tag)
    for cs in c_structs(b.mds[name]):
        if cs.struct is None:
            continue
        s, cls = cs.struct, py_class(b, name, cs.ctype)
        ints, floats = value_leaves(s)
        # A size mismatch would make the C probes overrun the buffer; fail first.
        assert getattr(b.lib, f"sizeof_{cs.ctype}")() == cs.size == ctypes.sizeof(cls)
        for trial in range(TRIALS):
            rng = random.Random(f"c2py:{tag}:{cs.ctype}:{trial}")
            want = c_fill_values(s, rng)
            iv = b.ffi.new("int64_t[]", [c_int(lf.prim, int(want[lf.expr])) for lf in ints] or 1)
            fv = b.ffi.new("double[]", [float(want[lf.expr]) for lf in floats] or 1)
            buf = b.ffi.new("unsigned char[]", cs.size)
            getattr(b.lib, f"fill_{cs.ctype}")(buf, iv, fv)
            data = bytes(b.ffi.buffer(buf))
            obj = cls.from_buffer_copy(data)
            assert bytes(obj) == data
            assert_leaves_equal(py_read(obj, s), want, f"{cs.ctype} read in Python")
            assert_leaves_equal(model_read(data, s), want, f"{cs.ctype} at model offsets")
            for leaf in leaves(s):
                if leaf.prim is None:
                    assert data[leaf.offset : leaf.offset + 8] == bytes(8), leaf.expr


@pytest.mark.parametrize("case", CASES, ids=case_id)
def test_python_to_c(built: Any, case: tuple[str, str]) -> None:
    tag, name = case
    b = built(tag)
    for cs in c_structs(b.mds[name]):
        if cs.struct is None:
            continue
        s, cls = cs.struct, py_class(b, name, cs.ctype)
        ints, floats = value_leaves(s)
        # A size mismatch would make the C probes overrun the buffer; fail first.
        assert getattr(b.lib, f"sizeof_{cs.ctype}")() == cs.size == ctypes.sizeof(cls)
        for trial in range(TRIALS):
            rng = random.Random(f"py2c:{tag}:{cs.ctype}:{trial}")
            obj = cls()
            want = py_write(obj, s, rng)
            data = bytes(obj)
            assert len(data) == cs.size
            iv = b.ffi.new("int64_t[]", max(len(ints), 1))
            fv = b.ffi.new("double[]", max(len(floats), 1))
            getattr(b.lib, f"read_{cs.ctype}")(b.ffi.from_buffer(data), iv, fv)
            got: dict[str, int | float] = {}
            for i, leaf in enumerate(ints):
                assert leaf.prim is not None
                got[leaf.expr] = from_c_int(leaf.prim, iv[i])
            got |= {leaf.expr: fv[i] for i, leaf in enumerate(floats)}
            assert_leaves_equal(got, want, f"{cs.ctype} read in C")
            assert_leaves_equal(model_read(data, s), want, f"{cs.ctype} at model offsets")


@pytest.mark.parametrize("tag", list(DIRS))
def test_headers_compile_strictly(tag: str, tmp_path: Path) -> None:
    """All mds of a dir in one C and one C++ header, through the command line."""
    names = md_names(DIRS[tag])
    for suffix, cmd in [
        (".h", ["gcc", "-std=c11", "-Wall", "-Wextra", "-Werror", "-pedantic", "-x", "c"]),
        (".hpp", ["g++", "-std=c++17", "-Wall", "-Wextra", "-Werror", "-pedantic", "-x", "c++"]),
    ]:
        out = tmp_path / f"all{suffix}"
        gen = subprocess.run(
            [sys.executable, "-m", "ln_generate", "-o", str(out), "--md-dir", str(DIRS[tag]),
             *names],
            cwd=REPO, capture_output=True, text=True,
        )
        assert gen.returncode == 0, gen.stderr
        cc = subprocess.run([*cmd, "-fsyntax-only", str(out)], capture_output=True, text=True)
        assert cc.returncode == 0, cc.stderr

