"""ROS 2 names of ln names (docs/recording.md "The ROS 2 mapping"): md name -> `pkg/msg/Type`,
md field name -> a lower snake field name.  Pure functions, deterministic, no md loading."""

from __future__ import annotations

import re

_CAMEL = re.compile(r"(?<=[a-z0-9])(?=[A-Z])|(?<=[A-Z])(?=[A-Z][a-z])")
_NOT_SNAKE = re.compile(r"[^a-z0-9_]+")
_UNDERSCORES = re.compile(r"_{2,}")
_WORDS = re.compile(r"[A-Za-z0-9]+")
DEFAULT_PACKAGE = "ln"


def snake(name: str, empty: str, digit_prefix: str) -> str:
    """`name` as a ROS lower snake name (`[a-z][a-z0-9_]*`, no `__`, no trailing `_`):
    an underscore between a lower case letter or digit and an upper case one (and before the
    last capital of a run followed by lower case: `HTTPServer` -> `http_server`), lower case,
    every run of other characters as one `_`, `_` runs collapsed, leading and trailing `_`
    dropped; `empty` if nothing is left, `digit_prefix` before a leading digit."""
    text = _CAMEL.sub("_", name).lower()
    text = _UNDERSCORES.sub("_", _NOT_SNAKE.sub("_", text)).strip("_")
    if not text:
        return empty
    return digit_prefix + text if text[0].isdigit() else text


def package_name(md_name: str) -> str:
    """The ROS package of an md: its folders joined with `_`, as snake(); `ln` without one."""
    folders = md_name.split("/")[:-1]
    return snake("_".join(folders), DEFAULT_PACKAGE, "ln_") if folders else DEFAULT_PACKAGE


def message_name(md_name: str) -> str:
    """The ROS message name of an md: the words (runs of letters and digits) of its last name
    part, each with its first letter upper case, joined (`joint_state` -> `JointState`,
    `jointState` -> `JointState`); `Msg` if there is none, `M` before a leading digit."""
    words = _WORDS.findall(md_name.split("/")[-1])
    text = "".join(w[0].upper() + w[1:] for w in words)
    if not text:
        return "Msg"
    return "M" + text if text[0].isdigit() else text


def ros2_type_name(md_name: str) -> str:
    """`robot/joint_state` -> `robot/msg/JointState`; `a/b/c` -> `a_b/msg/C`; `x` -> `ln/msg/X`."""
    return f"{package_name(md_name)}/msg/{message_name(md_name)}"


def dds_type_name(ros_type: str) -> str:
    """`pkg/msg/Type` -> `pkg::msg::dds_::Type_`, the name rmw implementations announce."""
    package, _, name = ros_type.split("/")
    return f"{package}::msg::dds_::{name}_"


def field_names(names: list[str]) -> list[str]:
    """The ROS field names of one struct's md field names, in order: snake() of each (`field`
    if nothing is left, `f_` before a leading digit); a name already taken in the struct gets
    `_2`, `_3`, ... (the first free one)."""
    out: list[str] = []
    taken: set[str] = set()
    for name in names:
        base = snake(name, "field", "f_")
        candidate, n = base, 2
        while candidate in taken:
            candidate, n = f"{base}_{n}", n + 1
        taken.add(candidate)
        out.append(candidate)
    return out
