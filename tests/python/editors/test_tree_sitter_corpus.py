"""The Tree-sitter test corpus of each grammar under editors/ (test/corpus/*.txt), run with
the Python bindings against the committed generated parser: the same cases `tree-sitter
test` runs, compared the same way (normalized S-expressions, field names only where the
expectation has them; `:error` cases need a syntax error somewhere)."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from .ts_corpus import CorpusCase, has_fields, normalize, read_corpus, strip_fields
from .ts_grammars import GRAMMARS, Grammar, grammar_root


def _corpus_files(name: str) -> list:
    return sorted((grammar_root(name) / "test" / "corpus").glob("*.txt"))


def _cases() -> list:
    return [
        pytest.param(name, case, id=f"{name}:{file.name}:{case.line}")
        for name in GRAMMARS
        for file in _corpus_files(name)
        for case in read_corpus(file)
    ]


@pytest.mark.parametrize("name", GRAMMARS)
def test_grammar_has_a_corpus(grammar: Callable[[str], Grammar], name: str) -> None:
    grammar(name)  # skips while the grammar is not generated
    files = _corpus_files(name)
    assert files, f"{grammar_root(name)}/test/corpus has no *.txt"
    for file in files:
        assert read_corpus(file), f"{file}: no test cases found"


@pytest.mark.parametrize(("name", "case"), _cases())
def test_corpus_case(grammar: Callable[[str], Grammar], name: str, case: CorpusCase) -> None:
    unknown = case.attributes - {":error"}
    assert not unknown, f"{case.where}: attributes this runner does not implement: {unknown}"
    root = grammar(name).parse(case.source).root_node
    if ":error" in case.attributes:
        assert root.has_error, f"{case.where}: {case.name}: expected a syntax error, got {root}"
        return
    actual = normalize(str(root))
    if not has_fields(case.expected):
        actual = strip_fields(actual)
    assert actual == case.expected, f"{case.where}: {case.name}"
