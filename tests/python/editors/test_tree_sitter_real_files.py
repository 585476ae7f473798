"""Every real file of each language parses with no ERROR and no MISSING node: the `.lnc`
configurations and mds written for the original Links and Nodes (../shared/real_ln, read
in place) and the project's own mds (message_definitions/, bench/md/). A failure names the
first such node as file:line:col. Without ../shared/real_ln those cases skip, outside CI."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from buildtree import REPO

from .ts_grammars import Grammar, first_problem

REAL_LN = REPO.parent / "shared" / "real_ln"
#: grammar -> (folder, how many files it must hold; None: whatever is there)
CORPORA: dict[str, list[tuple[Path, int | None]]] = {
    "lnc": [(REAL_LN / "lnc", 39)],
    "lnmd": [
        (REAL_LN / "md", 139),
        (REPO / "message_definitions", None),
        (REPO / "bench" / "md", None),
    ],
}
NOT_MD = {"SConscript"}  # what sits beside the mds in the project's md folders


def _files(folder: Path) -> list[Path]:
    return sorted(
        p
        for p in folder.rglob("*")
        if p.is_file()
        and p.name not in NOT_MD
        and "__pycache__" not in p.parts
        and not p.name.startswith(".")
    )


def _params() -> list[Any]:
    params = []
    for name, folders in CORPORA.items():
        for folder, _ in folders:
            where = folder.relative_to(REPO.parent)
            params += [
                pytest.param(name, path, id=f"{name}:{path.relative_to(REPO.parent)}")
                for path in (_files(folder) if folder.is_dir() else [])
            ]
            if not folder.is_dir():
                params.append(pytest.param(name, folder, id=f"{name}:{where} (missing)"))
    return params


def _require(folder: Path) -> None:
    if folder.is_dir():
        return
    if os.environ.get("CI") or not folder.is_relative_to(REAL_LN):
        pytest.fail(f"{folder} is missing")
    pytest.skip(f"the real-world corpus {folder} is not here")


@pytest.mark.parametrize(
    ("name", "folder", "count"),
    [(name, folder, count) for name, folders in CORPORA.items() for folder, count in folders],
)
def test_corpus_is_complete(name: str, folder: Path, count: int | None) -> None:
    _require(folder)
    found = len(_files(folder))
    if count is None:
        assert found > 0, f"{folder}: no files"
    else:
        assert found == count, f"{folder}: {found} files, expected {count}"


@pytest.mark.parametrize(("name", "path"), _params())
def test_real_file_parses_cleanly(grammar: Callable[[str], Grammar], name: str, path: Path) -> None:
    _require(path if not path.is_file() else path.parent)
    language = grammar(name)
    source = path.read_bytes()
    tree = language.parse(source)
    problem = first_problem(path, source, tree.root_node)
    assert problem is None, problem
