"""The committed generated parser of each grammar under editors/ (src/parser.c,
grammar.json, node-types.json) is what `tree-sitter generate` makes of its grammar.js now,
at the ABI the committed parser.c declares: nobody changed the grammar without
regenerating. Needs tree-sitter-cli (`cargo install tree-sitter-cli`) and node."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from .ts_grammars import GRAMMARS, grammar_root

GENERATED = ("parser.c", "grammar.json", "node-types.json")


def _cli() -> str | None:
    cargo = Path.home() / ".cargo" / "bin" / "tree-sitter"
    return shutil.which("tree-sitter") or (str(cargo) if cargo.is_file() else None)


@pytest.mark.parametrize("name", GRAMMARS)
def test_generated_parser_is_up_to_date(tmp_path: Path, name: str) -> None:
    root = grammar_root(name)
    if not (root / "src" / "parser.c").is_file():
        pytest.skip(f"editors/tree-sitter-{name} has no generated src/parser.c yet")
    cli = _cli()
    if cli is None or shutil.which("node") is None:
        pytest.skip("tree-sitter-cli or node is not installed (only needed to regenerate)")
    committed = root / "src" / "parser.c"
    abi = re.search(r"^#define LANGUAGE_VERSION (\d+)$", committed.read_text(), re.M)
    assert abi, f"{committed}: no LANGUAGE_VERSION"
    copy = tmp_path / root.name
    shutil.copytree(root, copy, ignore=shutil.ignore_patterns("node_modules", "build"))
    done = subprocess.run(
        [cli, "generate", "--abi", abi.group(1)],
        cwd=copy,
        capture_output=True,
        text=True,
        env={**os.environ, "TREE_SITTER_DIR": str(tmp_path / "config")},
    )
    assert done.returncode == 0, f"tree-sitter generate failed:\n{done.stderr}"
    stale = [
        f for f in GENERATED if (copy / "src" / f).read_bytes() != (root / "src" / f).read_bytes()
    ]
    assert not stale, (
        f"{root}/src: {stale} differ from what grammar.js generates; run "
        f"`tree-sitter generate --abi {abi.group(1)}` in {root}"
    )
