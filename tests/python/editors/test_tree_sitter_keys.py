"""The .lnc grammar's highlight query names the known keys in a list of its own (Tree-sitter
queries cannot import); it must stay the reader's set: process_keys.KNOWN and the KEYS (and
IGNORED) of the instance, state, group and network sections, plus `undef`."""

from __future__ import annotations

import re
from pathlib import Path

from links_and_nodes.manager.config import process_keys, sections

HIGHLIGHTS = (Path(__file__).resolve().parents[3] / "editors" / "tree-sitter-lnc" / "queries"
              / "highlights.scm")


def _reader_keys() -> set[str]:
    keys = set(process_keys.KNOWN) | {"undef"}
    for section in (sections.InstanceSection, sections.StateSection, sections.GroupSection,
                    sections.NetworkSection):
        keys |= set(section.KEYS) | set(getattr(section, "IGNORED", ()))
    return keys


def _query_lists() -> list[set[str]]:
    """Every `#any-of? @property` / `#not-any-of? @variable` word list of the query."""
    text = HIGHLIGHTS.read_text()
    lists = re.findall(r"\(#(?:not-)?any-of\? @(?:property|variable)\s+((?:\"[^\"]*\"\s*)+)\)",
                       text)
    return [set(re.findall(r"\"([^\"]*)\"", words)) for words in lists]


def test_known_key_lists_are_the_readers() -> None:
    lists = _query_lists()
    assert lists, f"no key list found in {HIGHLIGHTS}"
    expected = _reader_keys()
    for words in lists:
        assert words == expected, (f"highlights.scm: missing {sorted(expected - words)}, "
                                   f"extra {sorted(words - expected)}")
