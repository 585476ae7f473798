"""The ROS 2 message types of an md: the md and every md it nests as `RosType`s, their .msg
text, and the `ros2msg` schema (the md's type first, then each nested type once).

The mapping (docs/recording.md "The ROS 2 mapping"): intN_t/uintN_t -> intN/uintN, float ->
float32, double -> float64, a single char -> uint8 (its byte), char[N] -> string<=N (the text
up to the first NUL), T[N] -> T[N], a nested md -> its own type.  Services, events and mds
with a dynamic field (anywhere, nested too) are refused with CdrError: a topic sample holds
the field's pointer, not its data.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from .errors import CdrError
from .names import field_names, ros2_type_name

if TYPE_CHECKING:
    from ln_generate import MessageDef, Struct

#: ROS 2 primitive of each ln primitive (a char array is a string instead).
PRIMITIVES = {
    "char": "uint8", "int8_t": "int8", "uint8_t": "uint8", "int16_t": "int16",
    "uint16_t": "uint16", "int32_t": "int32", "uint32_t": "uint32", "int64_t": "int64",
    "uint64_t": "uint64", "float": "float32", "double": "float64",
}
SEPARATOR = "=" * 80


@dataclass(frozen=True)
class RosField:
    name: str
    type: str  # a primitive ("float64", "string", ...) or a nested type "pkg/msg/Type"
    array_size: int = 0  # elements of a fixed array; 0: not an array
    string_bound: int = 0  # string<=N; 0: unbounded (or not a string)

    @property
    def is_nested(self) -> bool:
        return "/" in self.type

    def msg_line(self) -> str:
        """The field as a line of a .msg file (a nested type as `pkg/Type`)."""
        if self.is_nested:
            package, _, name = self.type.split("/")
            text = f"{package}/{name}"
        elif self.type == "string" and self.string_bound:
            text = f"string<={self.string_bound}"
        else:
            text = self.type
        suffix = f"[{self.array_size}]" if self.array_size else ""
        return f"{text}{suffix} {self.name}"


@dataclass(frozen=True)
class RosType:
    name: str  # "pkg/msg/Type"
    fields: tuple[RosField, ...]

    def msg_text(self) -> str:
        return "".join(f.msg_line() + "\n" for f in self.fields)


def schema_text(types: list[RosType]) -> str:
    """The ros2msg schema of `types[0]` (types[1:]: every type it nests, each once).  A nested
    type's header names it as its fields do, `pkg/Type` (as rosbag2 writes it): Foxglove's
    parser looks nested types up by exactly that name."""
    parts = [types[0].msg_text()]
    parts += [f"{SEPARATOR}\nMSG: {t.name.replace('/msg/', '/')}\n{t.msg_text()}"
              for t in types[1:]]
    return "".join(parts)


def load_md(md_name: str, md_dirs: list[str] | None = None) -> MessageDef:
    """md `md_name` as ln_generate finds it: `md_dirs` (else the directories given to
    ln.add_message_definition_dir) before the built-in ones and LN_MESSAGE_DEFINITION_DIRS."""
    from ln_generate import MdRegistry, default_md_dirs

    return MdRegistry(default_md_dirs(search_dirs(md_dirs))).load(md_name)


def search_dirs(md_dirs: list[str] | None) -> list[str]:
    from .. import md_loader

    return [str(d) for d in md_dirs] if md_dirs is not None else list(md_loader._extra_dirs)


def topic_struct(md: MessageDef) -> Struct:
    """The struct of a message md that can be a ROS 2 topic type; CdrError otherwise."""
    if md.kind != "message":
        article = "an" if md.kind == "event" else "a"
        raise CdrError(f"md '{md.name}' is {article} {md.kind}: only messages map to ROS 2 "
                       "topic types")
    _refuse_dynamic(md.name, md.struct, "")
    return md.struct


def _refuse_dynamic(md_name: str, struct: Struct, prefix: str) -> None:
    from ln_generate import Struct

    for f in struct.fields:
        if f.kind == "dynamic":
            raise CdrError(
                f"md '{md_name}': field '{prefix}{f.name}' is dynamic ({_type_of(f.type)}* "
                f"{f.name}): a topic sample holds its pointer, not its data, so the md has no "
                "ROS 2 topic type")
        if isinstance(f.type, Struct):
            _refuse_dynamic(md_name, f.type, f"{prefix}{f.name}.")


def _type_of(t: object) -> str:
    return getattr(t, "md_name", None) or getattr(t, "name", "?")


def ros_field(f: object, name: str) -> RosField:
    """The RosField of ln field `f` (a scalar or a fixed array) under ROS name `name`."""
    from ln_generate import Field, Struct

    assert isinstance(f, Field) and f.kind != "dynamic"
    array = f.count if f.kind == "array" else 0
    if isinstance(f.type, Struct):
        return RosField(name, ros2_type_name(f.type.md_name), array)
    if f.type.kind == "char" and f.kind == "array":
        return RosField(name, "string", 0, f.count)
    return RosField(name, PRIMITIVES[f.type.name], array)


def struct_type(struct: Struct) -> RosType:
    names = field_names([f.name for f in struct.fields])
    return RosType(ros2_type_name(struct.md_name),
                   tuple(ros_field(f, n) for f, n in zip(struct.fields, names, strict=True)))


def md_types(md: MessageDef) -> list[RosType]:
    """The RosTypes of a topic md: its own first, then each nested md's once (CdrError for an
    md without a topic mapping or two nested mds with one ROS 2 name)."""
    struct = topic_struct(md)
    types = [struct_type(struct)]
    owner = {types[0].name: md.name}
    for nested in struct.nested_structs():
        t = struct_type(nested)
        other = owner.setdefault(t.name, nested.md_name)
        if other == nested.md_name and any(x.name == t.name for x in types):
            continue
        if other != nested.md_name:
            raise CdrError(f"md '{md.name}': the mds '{other}' and '{nested.md_name}' both map "
                           f"to the ROS 2 type '{t.name}'")
        types.append(t)
    return types
