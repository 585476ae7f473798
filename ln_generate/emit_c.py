"""Emits a C11 header: packed structs, constants, and static asserts on the layout.

Each md sits in its own `#ifndef LN_MD_<NAME>` block whose value is the layout
hash, so two generated headers may share an md, but never with different layouts.
"""

from __future__ import annotations

from pathlib import Path

from .emit_common import banner, comment_text, guard_name, ordered
from .model import MessageDef, Primitive, Struct
from .names import c_name


def struct_c_name(s: Struct) -> str:
    base = c_name(s.md_name)
    return f"{base}_{s.section}_t" if s.section else f"{base}_t"


def _field_lines(s: Struct) -> list[str]:
    if not s.fields:
        return ["    uint8_t _ln_empty; /* C has no empty structs; not part of the layout */"]
    lines = []
    for f in s.fields:
        t = f.type.c_type if isinstance(f.type, Primitive) else struct_c_name(f.type)
        tail = f" /* {comment_text(f.doc)} */" if f.doc else ""
        if f.kind == "dynamic":
            lines.append(f"    uint32_t {f.len_name};")
            lines.append(f"    {t}* {f.name};{tail}")
        elif f.kind == "array":
            lines.append(f"    {t} {f.name}[{f.count}];{tail}")
        else:
            lines.append(f"    {t} {f.name};{tail}")
    return lines


def _asserts(ctype: str, s: Struct, what: str) -> list[str]:
    size = s.size or 1
    out = [f'LN_MD_STATIC_ASSERT(sizeof({ctype}) == {size}, "{what}: size");']
    for f in s.fields:
        offsets = [(f.len_name, f.offset), (f.name, f.pointer_offset)] if f.kind == "dynamic" else [(f.name, f.offset)]
        for member, off in offsets:
            out.append(
                f"LN_MD_STATIC_ASSERT(offsetof({ctype}, {member}) == {off}, "
                f'"{what}: offset of {member}");'
            )
    return out


def emit_md(md: MessageDef) -> list[str]:
    base = c_name(md.name)
    macro = base.upper()
    marker = f"LN_MD_{macro}"
    hash_lit = f"0x{md.layout_hash:016x}ULL"
    doc = comment_text(md.doc)
    out = [f"/* {md.name} ({md.kind}){': ' + doc if doc else ''} */"]
    out += [f"#ifndef {marker}", f"#define {marker} {hash_lit}", "#pragma pack(push, 1)"]
    asserts: list[str] = []
    if any(s.has_dynamic for s in md.sections.values()):
        asserts.append(
            f'LN_MD_STATIC_ASSERT(sizeof(void*) == 8, "{md.name}: dynamic fields need 64-bit pointers");'
        )
    for name, s in md.sections.items():
        ctype = struct_c_name(s)
        tag = ctype[:-2]
        out += [f"typedef struct {tag} {{", *_field_lines(s), f"}} {ctype};"]
        asserts += _asserts(ctype, s, f"{md.name}{' ' + name if name else ''}")
    if md.kind != "message":
        members = [f"    {struct_c_name(s)} {'req' if n == 'request' else 'resp' if n == 'response' else n};"
                   for n, s in md.sections.items()]
        out += [f"typedef struct {base} {{", *members, f"}} {base}_t;"]
    out.append("#pragma pack(pop)")
    out.append(f'#define {macro}_MD_NAME "{md.name}"')
    out.append(f'#define {macro}_SIGNATURE "{md.signature}"')
    out.append(f"#define {macro}_LAYOUT_HASH UINT64_C(0x{md.layout_hash:016x})")
    for name, s in md.sections.items():
        suffix = f"_{name.upper()}" if name else ""
        out.append(f"#define {macro}{suffix}_SIZE {s.size}")
    if md.kind == "message":  # the (md name, layout hash, size) arguments of ln_publish/subscribe
        out.append(f"#define {macro}_MD {macro}_MD_NAME, {macro}_LAYOUT_HASH, sizeof({base}_t)")
    if md.kind == "service":  # the (md name, layout hash, signature) arguments of ln_get_service
        out.append(f"#define {macro}_SERVICE {macro}_MD_NAME, {macro}_LAYOUT_HASH, {macro}_SIGNATURE")
    if md.kind == "event":  # the (md name, layout hash, signature) arguments of ln_event_*
        out.append(f"#define {macro}_EVENT {macro}_MD_NAME, {macro}_LAYOUT_HASH, {macro}_SIGNATURE")
    out += asserts
    out += [f"#elif {marker} != {hash_lit}",
            f'#error "{md.name}: included from two generated headers with different layouts"',
            "#endif", ""]
    return out


def emit(requested: list[MessageDef], output: Path, version: str) -> str:
    mds = ordered(requested)
    guard = guard_name(output)
    lines = ["/*", *(f" * {b}" for b in banner(version, mds)), " */"]
    lines += [f"#ifndef {guard}", f"#define {guard}", "",
              "#include <stddef.h>", "#include <stdint.h>", "",
              "#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__",
              '#error "links_and_nodes message layouts are little-endian"',
              "#endif", "",
              "#ifndef LN_MD_STATIC_ASSERT",
              "#ifdef __cplusplus",
              "#define LN_MD_STATIC_ASSERT(cond, msg) static_assert(cond, msg)",
              "#else",
              "#define LN_MD_STATIC_ASSERT(cond, msg) _Static_assert(cond, msg)",
              "#endif",
              "#endif", ""]
    for md in mds:
        lines += emit_md(md)
    lines += [f"#endif /* {guard} */", ""]
    return "\n".join(lines)
