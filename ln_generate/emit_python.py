"""Emits a Python module of ctypes Structures (`_pack_ = 1`, little-endian).

The classes derive from `links_and_nodes.md_types.LnStruct`, which turns numeric
array fields into numpy views and adds `to_dict`/`from_dict`; the module carries
the same signature and layout hash as the C and C++ headers.
"""

from __future__ import annotations

from pathlib import Path

from .emit_common import banner, comment_text, ordered
from .model import MessageDef, Primitive, Struct
from .names import c_name

_MEMBER = {"request": "req", "response": "resp", "connect": "connect", "call": "call"}


def class_name(s: Struct) -> str:
    base = c_name(s.md_name)
    return f"{base}_{s.section}_t" if s.section else f"{base}_t"


def _elem(f_type: Primitive | Struct) -> str:
    return f"ctypes.{f_type.ctypes_type}" if isinstance(f_type, Primitive) else class_name(f_type)


def _doc(md: MessageDef) -> str:
    """The md's comment as docstring text: backslashes and double quotes escaped."""
    return comment_text(md.doc).replace("\\", "\\\\").replace('"', '\\"')


def _tail(out: list[str], cls: str, specs: list[str]) -> list[str]:
    out += ["    _ln_specs_ = (", *(f"        {sp}," for sp in specs), "    )"]
    return [*out, "", "", f"finalize({cls})", "", ""]


def _struct_class(md: MessageDef, s: Struct) -> list[str]:
    cls = class_name(s)
    title = f"{md.name} {s.section}" if s.section else md.name
    doc = _doc(md) if md.doc and not s.section else ""
    out = [f"class {cls}(LnStruct):", f'    """{title}{": " + doc if doc else ""}"""', "",
           "    _pack_ = 1", "    _fields_ = ["]
    specs = []
    if not s.fields:
        out.append('        ("_ln_empty", ctypes.c_uint8),  # no empty ctypes structs; not in the layout')
    for f in s.fields:
        elem = _elem(f.type)
        tail = f"  # {comment_text(f.doc)}" if f.doc else ""
        if f.kind == "dynamic":
            out.append(f'        ("{f.len_name}", ctypes.c_uint32),')
            out.append(f'        ("{f.name}", ctypes.POINTER({elem})),{tail}')
        elif f.kind == "array":
            out.append(f'        ("{f.name}", {elem} * {f.count}),{tail}')
        else:
            out.append(f'        ("{f.name}", {elem}),{tail}')
        specs.append(f'("{f.name}", "{f.kind}", {elem}, {f.count})')
    out.append("    ]")
    out.append(f'    MD_NAME = "{md.name}"')
    if not s.section:
        out.append(f'    SIGNATURE = "{md.signature}"')
        out.append(f"    LAYOUT_HASH = 0x{md.layout_hash:016x}")
    out.append(f"    SIZE = {s.size}")
    return _tail(out, cls, specs)


def _combined_class(md: MessageDef) -> list[str]:
    cls = f"{c_name(md.name)}_t"
    members = [(_MEMBER[n], class_name(s)) for n, s in md.sections.items()]
    doc = _doc(md)
    out = [f"class {cls}(LnStruct):", f'    """{md.name} ({md.kind}){": " + doc if doc else ""}"""',
           "", "    _pack_ = 1", "    _fields_ = ["]
    out += [f'        ("{m}", {c}),' for m, c in members]
    out += ["    ]", f'    MD_NAME = "{md.name}"', f'    KIND = "{md.kind}"',
            f'    SIGNATURE = "{md.signature}"', f"    LAYOUT_HASH = 0x{md.layout_hash:016x}"]
    return _tail(out, cls, [f'("{m}", "scalar", {c}, 1)' for m, c in members])


def emit(requested: list[MessageDef], output: Path, version: str) -> str:
    mds = ordered(requested)
    lines = [*(f"# {b}" for b in banner(version, mds)),
             '"""Message types generated from links_and_nodes message definitions."""', "",
             "import ctypes", "", "from links_and_nodes.md_types import LnStruct, finalize", "", ""]
    for md in mds:
        for s in md.sections.values():
            lines += _struct_class(md, s)
        if md.kind != "message":
            lines += _combined_class(md)
    entries = "".join(f'    "{md.name}": {c_name(md.name)}_t,\n' for md in mds)
    lines.append("#: md name -> generated class")
    lines.append("MESSAGES = {\n" + entries + "}")
    lines.append("")
    return "\n".join(lines)
