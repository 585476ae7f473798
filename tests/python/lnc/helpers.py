"""Helpers of the `.lnc` tests: write a tree of configuration files and load it."""

from __future__ import annotations

import textwrap
from pathlib import Path

from links_and_nodes.manager.config import Config, load
from links_and_nodes.manager.config.model import Location

HEAD = "instance\nname: demo\nmanager: :54414\n"


def cfg(body: str) -> str:
    """HEAD followed by `body`, dedented."""
    return HEAD + textwrap.dedent(body).lstrip("\n")


def write(root: Path, files: dict[str, str]) -> Path:
    """Write `files` (relative name -> dedented text) under `root`; returns the first."""
    first = None
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(textwrap.dedent(text).lstrip("\n"))
        first = first or path
    assert first is not None
    return first


def load_files(root: Path, files: dict[str, str], **kwargs: object) -> Config:
    return load(write(root, files), env=kwargs.pop("env", {}), **kwargs)  # type: ignore[arg-type]


def loc(path: Path, line: int, col: int) -> Location:
    return Location(str(path), line, col)
