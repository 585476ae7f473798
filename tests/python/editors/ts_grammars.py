"""The Tree-sitter grammars under editors/ as the tests load them: each compiled from its
committed src/ (parser.c, scanner.c if there is one) with `cc` and loaded through its
`tree_sitter_NAME()` entry point with the PyPI `tree-sitter` bindings, as editors do."""

from __future__ import annotations

import ctypes
import subprocess
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from buildtree import REPO

EDITORS = REPO / "editors"
GRAMMARS = ("lnc", "lnmd")  # editors/tree-sitter-NAME
QUERIES = ("highlights", "locals", "folds")
# A TSLanguage pointer goes to tree_sitter.Language in a capsule of this name (a plain int
# is deprecated); the name must live as long as the capsule, so it is a module constant.
_CAPSULE_NAME = b"tree_sitter.Language"
_capsule_new = ctypes.pythonapi.PyCapsule_New
_capsule_new.restype = ctypes.py_object
_capsule_new.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_void_p]


def grammar_root(name: str) -> Path:
    return EDITORS / f"tree-sitter-{name}"


@dataclass(frozen=True)
class Grammar:
    """A compiled grammar: its project folder, its Language and the library behind it."""

    name: str
    root: Path
    language: Any  # tree_sitter.Language
    library: ctypes.CDLL  # kept alive as long as the Language

    def parse(self, source: bytes) -> Any:
        import tree_sitter

        return tree_sitter.Parser(self.language).parse(source)

    def query(self, kind: str) -> Any:
        import tree_sitter

        text = (self.root / "queries" / f"{kind}.scm").read_text(encoding="utf-8")
        return tree_sitter.Query(self.language, text)

    def captures(self, kind: str, node: Any) -> dict[str, list[Any]]:
        """Capture name -> nodes of query `kind` over `node` (QueryCursor from 0.25 on)."""
        import tree_sitter

        query = self.query(kind)
        cursor = getattr(tree_sitter, "QueryCursor", None)
        return dict((cursor(query) if cursor else query).captures(node))


def compile_grammar(name: str, out_dir: Path) -> Path:
    """`cc -shared` of the grammar's src/ into out_dir; the path of the library."""
    src = grammar_root(name) / "src"
    sources = [str(p) for p in (src / "parser.c", src / "scanner.c") if p.is_file()]
    library = out_dir / f"tree-sitter-{name}.so"
    done = subprocess.run(
        ["cc", "-shared", "-fPIC", "-O1", f"-I{src}", *sources, "-o", str(library)],
        capture_output=True,
        text=True,
    )
    if done.returncode:
        pytest.fail(f"compiling {src}: cc exited with {done.returncode}\n{done.stderr}")
    return library


def load_grammar(name: str, library_path: Path) -> Grammar:
    import tree_sitter

    library = ctypes.CDLL(str(library_path))
    entry = getattr(library, f"tree_sitter_{name}")
    entry.restype = ctypes.c_void_p
    capsule = _capsule_new(entry(), _CAPSULE_NAME, None)  # what the bindings take
    return Grammar(name, grammar_root(name), tree_sitter.Language(capsule), library)


def first_problem(path: Path, source: bytes, root: Any) -> str | None:
    """`path:line:col: ERROR|MISSING ...` of the first error or missing node (pre-order),
    or None; the column counts characters, from 1."""
    node = root
    while True:
        if node.is_error or node.is_missing:
            break
        node = next((c for c in node.children if c.has_error), None)
        if node is None:
            return None if not root.has_error else f"{path}: has_error, but no node found"
    row, byte_col = node.start_point
    line = source.split(b"\n")[row] if source else b""
    col = len(line[:byte_col].decode("utf-8", errors="replace")) + 1
    what = f"MISSING {node.type}" if node.is_missing else "ERROR"
    snippet = source[node.start_byte : node.start_byte + 40].decode("utf-8", errors="replace")
    return f"{path}:{row + 1}:{col}: {what} node at {snippet!r}"
