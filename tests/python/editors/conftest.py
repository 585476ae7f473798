"""Fixtures of the editor-support tests: `grammar(NAME)`, the Tree-sitter grammar of
editors/tree-sitter-NAME compiled into this run's temporary directory (ts_grammars.py)."""

from __future__ import annotations

import shutil
from collections.abc import Callable

import pytest
from buildtree import missing_test_tool

from .ts_grammars import Grammar, compile_grammar, grammar_root, load_grammar


@pytest.fixture(scope="session")
def grammar(tmp_path_factory: pytest.TempPathFactory) -> Callable[[str], Grammar]:
    """grammar(NAME): compiled once per run (per xdist worker). Skips the test while that
    grammar has no generated src/parser.c yet."""
    try:
        import tree_sitter  # noqa: F401
    except ImportError:
        missing_test_tool("the tree-sitter Python package (requirements-dev.txt)")
    if shutil.which("cc") is None:
        missing_test_tool("a C compiler (cc)")
    out_dir = tmp_path_factory.mktemp("tree_sitter")
    built: dict[str, Grammar] = {}

    def get(name: str) -> Grammar:
        if name not in built:
            if not (grammar_root(name) / "src" / "parser.c").is_file():
                pytest.skip(f"editors/tree-sitter-{name} has no generated src/parser.c yet")
            built[name] = load_grammar(name, compile_grammar(name, out_dir))
        return built[name]

    return get
