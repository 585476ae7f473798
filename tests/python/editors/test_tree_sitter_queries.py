"""The queries of each grammar under editors/ (queries/highlights.scm, locals.scm,
folds.scm) compile against the grammar, and highlight a real file; for the md grammar,
what each query captures on hand-written sources, by node and position."""

from __future__ import annotations

from collections.abc import Callable

import pytest
from buildtree import REPO

from .ts_grammars import GRAMMARS, QUERIES, Grammar

REAL_LN = REPO.parent / "shared" / "real_ln"
#: a file of each language to highlight: the corpus's, else the project's own
SAMPLES = {
    "lnc": [REAL_LN / "lnc" / "module_jitter_measurement" / "test.lnc", REPO / "examples"],
    "lnmd": [
        REAL_LN
        / "md"
        / "service_provider_key_value__share_ln"
        / "robotkernel"
        / "key_value"
        / "list",
        REPO / "message_definitions" / "robot" / "set_gains",
    ],
}
MD_SERVICE = b"""# Gains.
define pose as "robot/pose"
service
request
double stiffness[6*6]   # Nm/rad
pose* targets
response
uint8_t accepted
"""


@pytest.mark.parametrize("kind", QUERIES)
@pytest.mark.parametrize("name", GRAMMARS)
def test_query_compiles(grammar: Callable[[str], Grammar], name: str, kind: str) -> None:
    language = grammar(name)
    path = language.root / "queries" / f"{kind}.scm"
    assert path.is_file(), f"{path} is missing"
    assert language.query(kind).pattern_count > 0, f"{path}: no patterns"


def _sample(name: str) -> bytes:
    for path in SAMPLES[name]:
        if path.is_file():
            return path.read_bytes()
        if path.is_dir():
            found = sorted(path.rglob("*.lnc"))
            if found:
                return found[0].read_bytes()
    pytest.fail(f"no sample file for {name}: {SAMPLES[name]}")


@pytest.mark.parametrize("name", GRAMMARS)
def test_highlights_capture_a_real_file(grammar: Callable[[str], Grammar], name: str) -> None:
    language = grammar(name)
    source = _sample(name)
    captures = language.captures("highlights", language.parse(source).root_node)
    assert "comment" in captures, f"no comment highlighted: {sorted(captures)}"
    assert any(n.startswith("keyword") for n in captures), f"no keyword: {sorted(captures)}"
    assert len(captures) >= 3, f"only {sorted(captures)}"


def _texts(captures: dict[str, list], name: str) -> list[tuple[str, tuple[int, int]]]:
    return [(n.text.decode(), n.start_point) for n in captures.get(name, [])]


def test_md_highlights_by_position(grammar: Callable[[str], Grammar]) -> None:
    md = grammar("lnmd")
    captures = md.captures("highlights", md.parse(MD_SERVICE).root_node)
    texts = {name: sorted(_texts(captures, name)) for name in captures}
    assert texts["keyword"] == [("request", (3, 0)), ("response", (6, 0)), ("service", (2, 0))]
    assert texts["keyword.import"] == [("as", (1, 12)), ("define", (1, 0))]
    assert texts["type.definition"] == [("pose", (1, 7))]
    assert texts["type"] == [("pose", (5, 0))]
    assert texts["type.builtin"] == [("double", (4, 0)), ("uint8_t", (7, 0))]
    assert texts["property"] == [("accepted", (7, 8)), ("stiffness", (4, 7)), ("targets", (5, 6))]
    assert texts["string.special.path"] == [('"robot/pose"', (1, 15))]
    assert texts["number"] == [("6", (4, 17)), ("6", (4, 19))]
    assert texts["operator"] == [("*", (4, 18))]
    assert texts["punctuation.special"] == [("*", (5, 4))]
    assert texts["comment"] == [("# Gains.", (0, 0)), ("# Nm/rad", (4, 24))]


def test_md_folds_and_locals(grammar: Callable[[str], Grammar]) -> None:
    md = grammar("lnmd")
    root = md.parse(MD_SERVICE).root_node
    folds = md.captures("folds", root)["fold"]
    assert sorted((n.start_point, n.end_point) for n in folds) == [
        ((3, 0), (5, 13)),
        ((6, 0), (8, 0)),
    ]
    local = md.captures("locals", root)
    assert _texts(local, "local.scope") == [(MD_SERVICE.decode(), (0, 0))]
    assert sorted(_texts(local, "local.definition")) == [
        ("accepted", (7, 8)),
        ("pose", (1, 7)),
        ("stiffness", (4, 7)),
        ("targets", (5, 6)),
    ]
    assert _texts(local, "local.reference") == [("pose", (5, 0))]
