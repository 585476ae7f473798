"""Emits a C++17 header: namespaced packed structs, constexpr constants, static asserts.

`robot/joint_state` becomes `robot::joint_state_t` with `robot::joint_state_signature`,
`..._layout_hash`, `..._md_name`; services nest `request_t req` / `response_t resp`.
Messages, services and events also get an `ln::md_traits` specialisation for ln.hpp.
"""

from __future__ import annotations

from pathlib import Path

from .emit_common import banner, comment_text, guard_name, ordered
from .model import MessageDef, Primitive, Struct
from .names import c_name

_CPP_PRIM = {"char": "char", "float": "float", "double": "double"}
_MEMBER = {"request": "req", "response": "resp", "connect": "connect", "call": "call"}


def split_name(md_name: str) -> tuple[list[str], str]:
    *ns, leaf = md_name.split("/")
    return ns, leaf


def qualified(s: Struct) -> str:
    ns, leaf = split_name(s.md_name)
    path = "::" + "::".join([*ns, f"{leaf}_t"])
    return f"{path}::{s.section}_t" if s.section else path


def _ptype(p: Primitive) -> str:
    return _CPP_PRIM.get(p.name, f"std::{p.name}")


def _members(s: Struct, indent: str) -> list[str]:
    if not s.fields:
        return [f"{indent}std::uint8_t _ln_empty;  // C++ structs are never empty; not in the layout"]
    out = []
    for f in s.fields:
        t = _ptype(f.type) if isinstance(f.type, Primitive) else qualified(f.type)
        tail = f"  // {comment_text(f.doc)}" if f.doc else ""
        if f.kind == "dynamic":
            out += [f"{indent}std::uint32_t {f.len_name};", f"{indent}{t}* {f.name};{tail}"]
        elif f.kind == "array":
            out.append(f"{indent}{t} {f.name}[{f.count}];{tail}")
        else:
            out.append(f"{indent}{t} {f.name};{tail}")
    return out


def _asserts(ctype: str, s: Struct, what: str) -> list[str]:
    out = [f'static_assert(sizeof({ctype}) == {s.size or 1}, "{what}: size");']
    for f in s.fields:
        offsets = [(f.len_name, f.offset), (f.name, f.pointer_offset)] if f.kind == "dynamic" else [(f.name, f.offset)]
        for member, off in offsets:
            out.append(f'static_assert(offsetof({ctype}, {member}) == {off}, "{what}: offset of {member}");')
    return out


def emit_md(md: MessageDef) -> list[str]:
    ns, leaf = split_name(md.name)
    marker = f"LN_MD_CPP_{c_name(md.name).upper()}"
    hash_lit = f"0x{md.layout_hash:016x}ULL"
    doc = comment_text(md.doc)
    out = [f"// {md.name} ({md.kind}){': ' + doc if doc else ''}",
           f"#ifndef {marker}", f"#define {marker} {hash_lit}"]
    if ns:
        out.append(f"namespace {'::'.join(ns)} {{")
    out.append("#pragma pack(push, 1)")
    asserts: list[str] = []
    if md.kind == "message":
        out += [f"struct {leaf}_t {{", *_members(md.struct, "    "), "};"]
        asserts += _asserts(f"{leaf}_t", md.struct, md.name)
    else:
        out.append(f"struct {leaf}_t {{")
        for name, s in md.sections.items():
            out += [f"    struct {name}_t {{", *_members(s, "        "), "    };"]
            asserts += _asserts(f"{leaf}_t::{name}_t", s, f"{md.name} {name}")
        out += [f"    {name}_t {_MEMBER[name]};" for name in md.sections]
        out.append("};")
    out.append("#pragma pack(pop)")
    out.append(f'inline constexpr char {leaf}_md_name[] = "{md.name}";')
    out.append(f'inline constexpr char {leaf}_signature[] = "{md.signature}";')
    out.append(f"inline constexpr std::uint64_t {leaf}_layout_hash = 0x{md.layout_hash:016x}ULL;")
    for name, s in md.sections.items():
        out.append(f"inline constexpr std::size_t {leaf}{'_' + name if name else ''}_size = {s.size};")
    if any(s.has_dynamic for s in md.sections.values()):
        out.append(f'static_assert(sizeof(void*) == 8, "{md.name}: dynamic fields need 64-bit pointers");')
    out += asserts
    if ns:
        out.append(f"}}  // namespace {'::'.join(ns)}")
    if md.kind in ("message", "service", "event"):
        prefix = "::".join(ns) + "::" if ns else ""
        out += [f"template <> struct ln::md_traits<::{prefix}{leaf}_t> {{",
                f"    static constexpr const char* md_name = {'::' + prefix}{leaf}_md_name;",
                f"    static constexpr std::uint64_t layout_hash = {hash_lit};"]
        if md.kind == "service":  # what ln_get_service and ln_get_service_provider take
            out += [f"    static constexpr const char* signature = ::{prefix}{leaf}_signature;",
                    f"    using request_type = ::{prefix}{leaf}_t::request_t;",
                    f"    using response_type = ::{prefix}{leaf}_t::response_t;"]
        if md.kind == "event":  # what ln.hpp's event and event_handler take
            out += [f"    static constexpr const char* signature = ::{prefix}{leaf}_signature;",
                    f"    using connect_type = ::{prefix}{leaf}_t::connect_t;",
                    f"    using call_type = ::{prefix}{leaf}_t::call_t;"]
        out.append("};")
    out += [f"#elif {marker} != {hash_lit}",
            f'#error "{md.name}: included from two generated headers with different layouts"',
            "#endif", ""]
    return out


def emit(requested: list[MessageDef], output: Path, version: str) -> str:
    mds = ordered(requested)
    guard = guard_name(output)
    lines = [*(f"// {b}" for b in banner(version, mds)),
             f"#ifndef {guard}", f"#define {guard}", "",
             "#include <cstddef>", "#include <cstdint>", "",
             "#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__",
             '#error "links_and_nodes message layouts are little-endian"',
             "#endif", "",
             "namespace ln {",
             "// md name and layout hash of a generated message type (ln.hpp ports use it);",
             "// for a service type also signature, request_type and response_type",
             "template <typename T> struct md_traits;",
             "}  // namespace ln", ""]
    for md in mds:
        lines += emit_md(md)
    lines += [f"#endif  // {guard}", ""]
    return "\n".join(lines)
