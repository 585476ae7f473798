"""ROS 2 view of ln topic mds: type names, the ros2msg schema, CDR bytes, the RIHS01 hash.

    from links_and_nodes import ros2
    ros2.ros2_type_name("robot/joint_state")    # "robot/msg/JointState"
    ros2.msg_schema("robot/tool_state")         # ros2msg text: the type, then its nested types
    c = ros2.codec("robot/joint_state")         # cached per (md, md directories)
    cdr = c.encode(raw)                         # raw ln bytes -> CDR (header 00 01 00 00)
    raw == c.decode(cdr)                        # bit-exact; CdrError(offset, field) if bad
    c.type_name, c.schema_text, c.message_size, c.type_hash
    ros2.rihs01("robot/joint_state")            # "RIHS01_<64 hex>"
    ros2.type_description("robot/joint_state")  # the TypeDescription the hash is taken of

md lookup is md_loader's (the directories given to ln.add_message_definition_dir, or
`md_dirs`, before the built-in ones).  The mapping and the naming rules are documented in
docs/recording.md "The ROS 2 mapping" and in names.py / types.py:
- type name: package = the md's folders joined with `_` as lower snake (`ln` without a
  folder), type = the words of the last name part in CamelCase: `robot/joint_state` ->
  `robot/msg/JointState`, `a/B-c/tool` -> `a_b_c/msg/Tool`;
- field names: lower snake (`jointPos` -> `joint_pos`, `X` -> `x`), a clash gets `_2`, ...;
- int8_t..uint64_t -> int8..uint64, float -> float32, double -> float64, char -> uint8,
  char[N] -> string<=N (accepted by rosidl, rosbags and mcap-ros2-support), T[N] -> T[N],
  a nested md -> its type;
- refused with CdrError (a ValueError): services, events, mds with a dynamic field.
Modules: errors.py (CdrError), names.py (naming rules), types.py (RosType model, .msg and
schema text), cdr.py (CdrCodec), rihs01.py (type description and hash).
"""

from __future__ import annotations

from .cdr import CdrCodec, codec
from .errors import CdrError
from .names import dds_type_name, ros2_type_name
from .rihs01 import describe, hash_types, rihs01, type_description
from .types import RosField, RosType, load_md, md_types


def msg_schema(md_name: str, md_dirs: list[str] | None = None) -> str:
    """The ros2msg schema text of a topic md: its type's .msg, then each nested type once
    after a line of 80 '=' and `MSG: pkg/Type` (as the fields name it)."""
    return codec(md_name, md_dirs).schema_text


__all__ = [
    "CdrCodec", "CdrError", "RosField", "RosType", "codec", "dds_type_name", "describe",
    "hash_types", "load_md", "md_types", "msg_schema", "rihs01", "ros2_type_name",
    "type_description",
]
