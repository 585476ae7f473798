"""Python message classes for md names, built at run time with ln_generate's Python emitter.

`message_class("robot/joint_state")` gives the same ctypes class a generated module would
contain; each md is parsed once per process and cached.  Lookup follows the generator's
order: directories added here first, then the built-in ones, then LN_MESSAGE_DEFINITION_DIRS.
"""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

from .md_types import LnStruct

_lock = threading.Lock()
_extra_dirs: list[str] = []
_classes: dict[str, type[LnStruct]] = {}


def add_message_definition_dir(path: str | Path) -> None:
    """Search `path` for message definitions before the built-in directories."""
    with _lock:
        p = str(path)
        if p not in _extra_dirs:
            _extra_dirs.append(p)
            _classes.clear()  # a new directory may shadow an md already loaded


def message_class(md_name: str) -> type[LnStruct]:
    """The ctypes class of md `md_name` (raises ln_generate.MdError for a bad definition)."""
    with _lock:
        cls = _classes.get(md_name)
        if cls is None:
            cls = _build(md_name)
            _classes[md_name] = cls
        return cls


def _build(md_name: str) -> type[LnStruct]:
    from ln_generate import MdRegistry, default_md_dirs  # only here: parsing is a setup cost
    from ln_generate.emit_python import emit

    registry = MdRegistry(default_md_dirs(_extra_dirs))
    md = registry.load(md_name)
    source = emit([md], Path(f"<md {md_name}>"), "runtime")
    namespace: dict[str, Any] = {"__name__": f"links_and_nodes.md.{md_name.replace('/', '.')}"}
    exec(compile(source, f"<md {md_name}>", "exec"), namespace)
    cls: type[LnStruct] = namespace["MESSAGES"][md_name]
    return cls
