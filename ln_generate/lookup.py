"""Finds md files by name in an ordered list of directories, safely.

An md name such as `robot/joint_state` is not a path: it is looked up as
`DIR/robot/joint_state` in each directory in turn (a `define` first next to the
md that has it) and may never leave that directory (no `..`, no absolute names,
no symlink pointing outside).
"""

from __future__ import annotations

import os
import re
from pathlib import Path

ENV_DIRS = "LN_MESSAGE_DEFINITION_DIRS"
_COMPONENT_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def builtin_md_dir() -> Path | None:
    """The built-in `message_definitions/`: in the source tree, else under PREFIX/share."""
    here = Path(__file__).resolve().parent
    source = here.parent / "message_definitions"
    if (source / "ln").is_dir():
        return source
    for ancestor in here.parents:
        installed = ancestor / "share" / "links_and_nodes" / "message_definitions"
        if installed.is_dir():
            return installed
    return None


def default_md_dirs(explicit: list[str] | None = None) -> list[Path]:
    """Lookup order: explicit dirs, the built-in dir, then LN_MESSAGE_DEFINITION_DIRS."""
    dirs = [Path(d) for d in explicit or []]
    builtin = builtin_md_dir()
    if builtin is not None:
        dirs.append(builtin)
    dirs += [Path(d) for d in os.environ.get(ENV_DIRS, "").split(":") if d]
    out: list[Path] = []
    for d in dirs:
        if d not in out:
            out.append(d)
    return out


def check_name(name: str) -> str | None:
    """Why `name` is not a valid md name, or None when it is."""
    if not name:
        return "empty message definition name"
    if name.startswith("/"):
        return f"message definition name '{name}' must be relative, not absolute"
    parts = name.split("/")
    if ".." in parts or "." in parts:
        return f"message definition name '{name}' escapes its directory"
    for part in parts:
        if not part:
            return f"message definition name '{name}' has an empty component"
        if not _COMPONENT_RE.match(part):
            return (
                f"message definition name '{name}': component '{part}' is not an "
                "identifier (letters, digits, '_')"
            )
    return None


class LookupError_(Exception):
    """Name invalid, not found, or resolving outside its directory."""


def _candidate(name: str, d: Path) -> Path | None:
    """`d/name` if it is a file inside `d`; raises LookupError_ if it escapes `d`."""
    candidate = d / name
    if not candidate.is_file():
        return None
    root = d.resolve()
    real = candidate.resolve()
    if not real.is_relative_to(root):
        raise LookupError_(
            f"message definition '{name}' in '{d}' resolves to '{real}', outside its directory"
        )
    return candidate


def find(name: str, dirs: list[Path], beside: tuple[Path, str] | None = None) -> tuple[str, Path, Path]:
    """(md name, md dir, file) of `name`; raises LookupError_ with a precise reason.

    `beside` is (md dir, md name) of the md whose `define` asks: as in the original
    LN, `name` is first looked up in that md's own directory, where it is called
    `<that md's folder>/name`; then in `dirs` as usual.
    """
    problem = check_name(name)
    if problem:
        raise LookupError_(problem)
    searched: list[Path] = []
    if beside is not None:
        root, asking = beside
        folder = asking.rpartition("/")[0]
        local = f"{folder}/{name}" if folder else name
        found = _candidate(local, root)
        if found is not None:
            return local, root, found
        searched.append(root / folder if folder else root)
    for d in dirs:
        found = _candidate(name, d)
        if found is not None:
            return name, d, found
    searched += [d for d in dirs if d not in searched]
    where = ", ".join(str(d) for d in searched) or "no directories"
    raise LookupError_(f"message definition '{name}' not found (searched: {where})")
