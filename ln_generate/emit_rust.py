"""Emits Rust for the `links-and-nodes` crate: packed C-layout structs, owned forms, services.

`robot/joint_state` becomes `robot::JointState` (folders are modules, the last component in
CamelCase).  A struct without dynamic fields is one `#[repr(C, packed)]` type (a topic type:
`links_and_nodes::Message`); one with dynamic fields anywhere inside has an owned form
(`Vec<T>`, `String`) for user code and a `...Raw` C form (count + pointer) that the crate's
service calls convert to and from (`links_and_nodes::ServiceData`).  A service md adds a unit
type implementing `links_and_nodes::Service`.  Sizes and offsets are asserted at compile time.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from .diagnostics import Diagnostic, Location, MdError
from .emit_common import banner, comment_text, ordered
from .model import MessageDef, Primitive, Struct

CRATE = "::links_and_nodes"
_PRIM = {"char": "u8", "int8_t": "i8", "uint8_t": "u8", "int16_t": "i16", "uint16_t": "u16",
         "int32_t": "i32", "uint32_t": "u32", "int64_t": "i64", "uint64_t": "u64",
         "float": "f32", "double": "f64"}
_SECTION = {"request": "Request", "response": "Response", "connect": "Connect", "call": "Call"}
#: Words an identifier may only be as a raw identifier (`r#type`).
RUST_KEYWORDS = frozenset(
    """as async await break const continue dyn else enum extern false fn for if impl in let loop
    match mod move mut pub ref return static struct trait true type unsafe use where while
    abstract become box do final gen macro override priv try typeof unsized virtual yield""".split()
)
#: Words that cannot be identifiers at all, not even raw ones.
RUST_UNUSABLE = frozenset(["crate", "self", "Self", "super", "_"])
_ALLOW = "#[allow(non_snake_case, non_camel_case_types, dead_code, clippy::all)]"


def ident(name: str) -> str:
    return f"r#{name}" if name in RUST_KEYWORDS else name


def camel(leaf: str) -> str:
    """`joint_state` -> `JointState`; the case of the rest of each word is kept."""
    out = "".join(w[:1].upper() + w[1:] for w in leaf.split("_"))
    if not out or out[0].isdigit():
        out = f"Md{out}"
    return out


def module_of(md_name: str) -> tuple[str, ...]:
    return tuple(md_name.split("/")[:-1])


def type_name(s: Struct) -> str:
    base = camel(s.md_name.split("/")[-1])
    return base + _SECTION[s.section] if s.section else base


def raw_name(s: Struct) -> str:
    """The C form: the type itself without dynamic fields, else `NameRaw`."""
    return f"{type_name(s)}Raw" if s.has_dynamic else type_name(s)


def path_to(here: tuple[str, ...], target: tuple[str, ...], name: str) -> str:
    if here == target:
        return name
    return "::".join([*(["super"] * len(here)), *(ident(p) for p in target), name])


def _doc(text: str, indent: str) -> list[str]:
    text = comment_text(text).replace("```", "'''")
    return [f"{indent}/// {text}"] if text else []


@dataclass
class _Ctx:
    here: tuple[str, ...]

    def owned(self, s: Struct) -> str:
        return path_to(self.here, module_of(s.md_name), type_name(s))

    def raw(self, s: Struct) -> str:
        return path_to(self.here, module_of(s.md_name), raw_name(s))

    def elem(self, t: Primitive | Struct, raw: bool) -> str:
        if isinstance(t, Primitive):
            return _PRIM[t.name]
        return self.raw(t) if raw else self.owned(t)


def _dyn(t: Primitive | Struct) -> bool:
    return isinstance(t, Struct) and t.has_dynamic


def _owned_fields(s: Struct, ctx: _Ctx) -> list[str]:
    out = []
    for f in s.fields:
        out += _doc(f.doc, "    ")
        elem = ctx.elem(f.type, raw=False)
        if f.kind == "dynamic":
            t = "::std::string::String" if elem == "u8" and f.type.name == "char" else f"::std::vec::Vec<{elem}>"
        elif f.kind == "array":
            t = f"[{elem}; {f.count}]"
        else:
            t = elem
        out.append(f"    pub {ident(f.name)}: {t},")
    return out


def _raw_fields(s: Struct, ctx: _Ctx) -> list[str]:
    out = []
    for f in s.fields:
        elem = ctx.elem(f.type, raw=True)
        if f.kind == "dynamic":
            out += [f"    pub {f.len_name}: u32,", f"    pub {ident(f.name)}: *const {elem},"]
        elif f.kind == "array":
            out.append(f"    pub {ident(f.name)}: [{elem}; {f.count}],")
        else:
            out.append(f"    pub {ident(f.name)}: {elem},")
    return out


def _default_impl(name: str, s: Struct) -> list[str]:
    init = [f"            {ident(f.name)}: ::core::array::from_fn(|_| ::core::default::Default::default()),"
            if f.kind == "array" else f"            {ident(f.name)}: ::core::default::Default::default(),"
            for f in s.fields]
    return [f"impl ::core::default::Default for {name} {{",
            "    fn default() -> Self {", f"        {name} {{", *init, "        }", "    }", "}"]


def _packed_impls(name: str, s: Struct) -> list[str]:
    """Debug and PartialEq by copying fields: a packed field must never be borrowed."""
    dbg = "".join(f'.field("{f.name}", &{{ self.{ident(f.name)} }})' for f in s.fields)
    eq = " && ".join(f"({{ self.{ident(f.name)} }} == {{ other.{ident(f.name)} }})" for f in s.fields)
    return [f"impl ::core::fmt::Debug for {name} {{",
            "    fn fmt(&self, f: &mut ::core::fmt::Formatter<'_>) -> ::core::fmt::Result {",
            f'        f.debug_struct("{name}"){dbg}.finish()', "    }", "}",
            f"impl ::core::cmp::PartialEq for {name} {{",
            f"    fn eq(&self, {'other' if eq else '_other'}: &Self) -> bool {{",
            f"        {eq or 'true'}", "    }", "}"]


def _asserts(name: str, s: Struct, what: str) -> list[str]:
    out = [f"const _: () = assert!(::core::mem::size_of::<{name}>() == {s.size}, "
           f'"{what}: size");']
    for f in s.fields:
        members = [(f.len_name, f.offset), (ident(f.name), f.pointer_offset)] if f.kind == "dynamic" \
            else [(ident(f.name), f.offset)]
        out += [f"const _: () = assert!(::core::mem::offset_of!({name}, {m}) == {off}, "
                f'"{what}: offset of {m}");' for m, off in members]
    return out


def _to_raw(f, ctx: _Ctx) -> list[str]:  # noqa: ANN001 - a model Field
    n = ident(f.name)
    if f.kind == "dynamic":
        ptr = (f"{CRATE}::wire::records_to_raw(&self.{n}, keep)?" if _dyn(f.type)
               else f"self.{n}.as_ptr()")
        return [f'            {f.len_name}: {CRATE}::wire::len(self.{n}.len(), "{f.name}")?,',
                f"            {n}: {ptr},"]
    if not _dyn(f.type):
        return [f"            {n}: self.{n},"]
    if f.kind == "array":
        return [f"            {n}: {CRATE}::wire::array_to_raw(&self.{n}, keep)?,"]
    return [f"            {n}: {CRATE}::ServiceData::to_raw(&self.{n}, keep)?,"]


def _from_raw(f) -> str:  # noqa: ANN001 - a model Field
    n = ident(f.name)
    if f.kind == "dynamic":
        if _dyn(f.type):
            value = f"{CRATE}::wire::records_from_raw(raw.{n}, raw.{f.len_name})?"
        elif isinstance(f.type, Primitive) and f.type.name == "char":
            value = f'{CRATE}::wire::string_from_raw(raw.{n}, raw.{f.len_name}, "{f.name}")?'
        else:
            value = f"{CRATE}::wire::vec_from_raw(raw.{n}, raw.{f.len_name})?"
    elif not _dyn(f.type):
        value = f"raw.{n}"
    elif f.kind == "array":
        value = f"{CRATE}::wire::array_from_raw(&{{ raw.{n} }})?"
    else:
        value = f"{CRATE}::ServiceData::from_raw(&{{ raw.{n} }})?"
    return f"                {n}: {value},"


def _service_data(s: Struct, ctx: _Ctx) -> list[str]:
    name, raw = type_name(s), raw_name(s)
    head = [f"// SAFETY: {raw} is the packed C layout of this section (asserted above); to_raw",
            "// points only into `self` and `keep`, from_raw reads only the counted elements.",
            f"unsafe impl {CRATE}::ServiceData for {name} {{", f"    type Raw = {raw};"]
    if not s.has_dynamic:
        return [*head,
                f"    fn to_raw(&self, _keep: &mut {CRATE}::wire::Keep) -> {CRATE}::Result<Self> {{",
                "        Ok(*self)", "    }",
                f"    unsafe fn from_raw(raw: &Self) -> {CRATE}::Result<Self> {{", "        Ok(*raw)",
                "    }", "}"]
    to = [line for f in s.fields for line in _to_raw(f, ctx)]
    frm = [_from_raw(f) for f in s.fields]
    return [*head,
            f"    fn to_raw(&self, keep: &mut {CRATE}::wire::Keep) -> {CRATE}::Result<{raw}> {{",
            "        let _ = &keep;", f"        Ok({raw} {{", *to, "        })", "    }",
            f"    unsafe fn from_raw(raw: &{raw}) -> {CRATE}::Result<Self> {{",
            "        let _ = &raw;", "        // SAFETY: the caller's promise (ServiceData::from_raw).",
            "        unsafe {", f"            Ok({name} {{", *frm, "            })", "        }",
            "    }", "}"]


def _struct(md: MessageDef, s: Struct, ctx: _Ctx) -> list[str]:
    name, raw = type_name(s), raw_name(s)
    what = f"{md.name}{' ' + s.section if s.section else ''}"
    title = f"md {md.name}" + (f", section {s.section}" if s.section else "")
    doc = comment_text(md.doc)
    out = [f"/// {title}{': ' + doc if doc and not s.section else ''}", _ALLOW]
    if s.has_dynamic:
        out += ["#[derive(Clone, Debug, PartialEq)]", f"pub struct {name} {{",
                *_owned_fields(s, ctx), "}", *_default_impl(name, s),
                f"/// The C layout of [`{name}`]: each dynamic field is a count and a pointer.",
                _ALLOW, "#[repr(C, packed)]", "#[derive(Clone, Copy)]", f"pub struct {raw} {{",
                *_raw_fields(s, ctx), "}"]
    else:
        out += ["#[repr(C, packed)]", "#[derive(Clone, Copy)]", f"pub struct {name} {{",
                *_owned_fields(s, ctx), "}", *_default_impl(name, s), *_packed_impls(name, s),
                f"// SAFETY: packed plain data of md {md.name} ({what}); any bits are valid.",
                f"unsafe impl {CRATE}::wire::Plain for {name} {{}}"]
    out += [_ALLOW, f"impl {name} {{", f"    /// Bytes of the C layout (`{c_size_macro(md, s)}`).",
            f"    pub const SIZE: usize = {s.size};"]
    if not s.section:
        out += _md_consts(md)
    out.append("}")
    if s.has_dynamic and any(f.kind == "dynamic" for f in s.fields):
        out.append('const _: () = assert!(::core::mem::size_of::<usize>() == 8, '
                   f'"{md.name}: dynamic fields need 64-bit pointers");')
    out += _asserts(raw, s, what) + _service_data(s, ctx)
    if md.kind == "message" and not s.has_dynamic:
        out += [f"// SAFETY: packed plain data with the layout of md {md.name} and its hash.",
                f"unsafe impl {CRATE}::Message for {name} {{",
                f'    const MD_NAME: &\'static str = "{md.name}";',
                f"    const LAYOUT_HASH: u64 = 0x{md.layout_hash:016x};", "}"]
    return out


def c_size_macro(md: MessageDef, s: Struct) -> str:
    base = md.name.replace("/", "_").upper()
    return f"{base}_{s.section.upper()}_SIZE" if s.section else f"{base}_SIZE"


def _md_consts(md: MessageDef) -> list[str]:
    return ["    /// The md name.", f'    pub const MD_NAME: &\'static str = "{md.name}";',
            "    /// ln_generate's layout hash of the md.",
            f"    pub const LAYOUT_HASH: u64 = 0x{md.layout_hash:016x};",
            "    /// The md's signature (docs/message_definitions.md).",
            f'    pub const SIGNATURE: &\'static str = "{md.signature}";']


def _marker(md: MessageDef) -> list[str]:
    name = camel(md.name.split("/")[-1])
    doc = comment_text(md.doc)
    out = [f"/// md {md.name} ({md.kind}){': ' + doc if doc else ''}", _ALLOW,
           "#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]", f"pub struct {name};",
           _ALLOW, f"impl {name} {{", *_md_consts(md), "}"]
    if md.kind == "service":
        req, resp = (type_name(md.sections[s]) for s in ("request", "response"))
        out += [f"// SAFETY: the name, hash and signature of md {md.name} and its section types.",
                f"unsafe impl {CRATE}::Service for {name} {{",
                f'    const MD_NAME: &\'static str = "{md.name}";',
                f"    const LAYOUT_HASH: u64 = 0x{md.layout_hash:016x};",
                f'    const SIGNATURE: &\'static str = "{md.signature}";',
                f"    type Request = {req};", f"    type Response = {resp};", "}"]
    return out


def emit_md(md: MessageDef) -> list[str]:
    ctx = _Ctx(module_of(md.name))
    out = [f"// {md.name} ({md.kind})"]
    for s in md.sections.values():
        out += _struct(md, s, ctx)
    if md.kind != "message":
        out += _marker(md)
    return out


def _names(md: MessageDef) -> list[str]:
    out = []
    for s in md.sections.values():
        out += [type_name(s), *([raw_name(s)] if s.has_dynamic else [])]
    if md.kind != "message":
        out.append(camel(md.name.split("/")[-1]))
    return out


def check_rust_names(mds: list[MessageDef]) -> None:
    """Refuse mds whose Rust names collide or cannot be Rust identifiers."""
    errors: list[Diagnostic] = []
    seen: dict[tuple[tuple[str, ...], str], MessageDef] = {}
    for md in mds:
        at = Location(str(md.path), 1, 1)
        for part in md.name.split("/")[:-1]:
            if part in RUST_UNUSABLE:
                errors.append(Diagnostic(at, f"md name '{md.name}': component '{part}' cannot "
                                             "be a Rust module name"))
        for n in _names(md):
            other = seen.setdefault((module_of(md.name), n), md)
            if other is not md:
                errors.append(Diagnostic(at, f"'{md.name}' and '{other.name}' both generate the "
                                             f"Rust type '{n}'; generate them into separate files"))
        for s in md.sections.values():
            errors += [Diagnostic(f.loc, f"field name '{f.name}' cannot be a Rust identifier")
                       for f in s.fields if f.name in RUST_UNUSABLE]
    if errors:
        raise MdError(errors)


@dataclass
class _Module:
    lines: list[str] = field(default_factory=list)
    children: dict[str, _Module] = field(default_factory=dict)


def _render(mod: _Module, depth: int) -> list[str]:
    pad = "    " * depth
    out = [pad + line if line else line for line in mod.lines]
    for name, child in mod.children.items():
        out += [_ALLOW] if depth == 0 else []
        out += [f"{pad}pub mod {ident(name)} {{", *_render(child, depth + 1), f"{pad}}}"]
    return out


def emit(requested: list[MessageDef], output: Path, version: str) -> str:
    mds = ordered(requested)
    check_rust_names(mds)
    root = _Module()
    for md in mds:
        mod = root
        for part in module_of(md.name):
            mod = mod.children.setdefault(part, _Module())
        mod.lines += emit_md(md)
    lines = [*(f"// {b}" for b in banner(version, mds)),
             "// Include it in a module: `mod msg { include!(concat!(env!(\"OUT_DIR\"), "
             "\"/messages.rs\")); }` (docs/message_definitions.md, \"Rust\").", ""]
    lines += _render(root, 0)
    lines.append("")
    return "\n".join(lines)
