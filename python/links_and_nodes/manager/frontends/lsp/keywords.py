"""Keywords of the `.lnc` language for hover and completion, from the reader's own tables
(sections.py, process_keys.py, keywords.py: the table docs/configuration.md is checked
against) and, in a source checkout, the description rows of docs/configuration.md."""

from __future__ import annotations

import functools
import re
from pathlib import Path

from ...config.directives import DIRECTIVES
from ...config.keywords import keyword_status
from ...config.lexer import SECTION_WORDS
from ...config.process_keys import FLAGS, IGNORED, LISTS, SCALARS
from ...config.sections import (
    GROUP_FLAGS,
    GroupSection,
    InstanceSection,
    LoggerSection,
    NetworkSection,
    StateSection,
    TopicsSection,
)
from .reading import Analysis, Header

DOCS = Path(__file__).resolve().parents[5] / "docs" / "configuration.md"
_ROW_RE = re.compile(r"\|\s*`([^`]+)`(?:\s*/\s*`[^`]+`)?\s*\|\s*(.*?)\s*\|(?:\s*(.*?)\s*\|)?\s*\Z")
_PROCESS_DIRECTIVES = ("use_template", "add_message_definition_dir")

SECTION_KEYS: dict[str, tuple[str, ...]] = {
    "instance": tuple(sorted(InstanceSection.KEYS)),
    "process": tuple(sorted({*SCALARS, *LISTS, *_PROCESS_DIRECTIVES})),
    "state": tuple(sorted(StateSection.KEYS)),
    "group": tuple(sorted(GroupSection.KEYS)),
    "network": tuple(sorted(NetworkSection.KEYS)),
    "logger": ("autostart",),
    "defines": ("undef",),
}
VALUE_WORDS = {"topics": TopicsSection.SETTINGS, "logger": LoggerSection.SETTINGS}
TOP_WORDS = tuple(sorted({*SECTION_WORDS, *DIRECTIVES, "ifdef", "ifndef"}))


def section_at(analysis: Analysis, path: str, line: int) -> Header | None:
    """The section header above a 0-based line of `path`, as the reader met it."""
    best = None
    for h in analysis.records.headers:
        if h.loc.file == path and h.loc.line <= line + 1 and (best is None
                                                             or h.loc.line >= best.loc.line):
            best = h
    return best


@functools.cache
def doc_rows() -> dict[tuple[str, str], str]:
    """(section, keyword) -> its description in docs/configuration.md (a `## X` chapter
    is "#x"; flags are in "process"); empty when the docs are not beside the package."""
    rows: dict[tuple[str, str], str] = {}
    try:
        text = DOCS.read_text()
    except OSError:
        return rows
    section = ""
    for line in text.splitlines():
        if line.startswith("#"):
            words = line.lstrip("#").split()
            word = words[0].lower() if words else ""
            section = word if line.startswith("### ") else "#" + word
            continue
        m = _ROW_RE.match(line.strip())
        if m and m.group(2) and not m.group(2).startswith("---"):
            word = m.group(1).split()[0].split(":")[0]
            rows.setdefault((section, word), m.group(2))
    return rows


def describe(word: str, section: str, in_flags: bool) -> str | None:
    """Markdown for a keyword, or None when it is none."""
    is_flag = in_flags and (word in FLAGS or word in GROUP_FLAGS)
    known = (is_flag or word in SECTION_WORDS or word in DIRECTIVES or word in SCALARS
             or word in LISTS or word in IGNORED or word in SECTION_KEYS.get(section, ()))
    if not known:
        return None
    status, note = keyword_status(word, "flag" if is_flag else "key")
    what = "flag" if is_flag else ("section" if word in SECTION_WORDS else
                                   "directive" if word in DIRECTIVES else f"{section} key")
    rows = doc_rows()
    text = rows.get(("process", word)) if is_flag else (
        rows.get((section, word)) or rows.get(("process", word)) or rows.get(("#directives", word)))
    parts = [f"**{word}** ({what}): {status}" + (f", {note}" if note else "")]
    if text:
        parts.append(text)
    return "\n\n".join(parts)
