"""Completion in `.lnc` files: the keys valid in the section at the cursor (and section
words and directives), process/state/group names in reference lists, hosts after `node:`,
templates after `use_template:`, flags, define names inside `%(`, md names."""

from __future__ import annotations

import re
from pathlib import Path

from lsprotocol import types as lsp

from ...config.expand import CONTEXT_BUILTINS, FUNCTIONS, GLOBAL_BUILTINS
from ...config.process_keys import FLAGS
from ...config.sections import GROUP_FLAGS
from .keywords import SECTION_KEYS, TOP_WORDS, section_at
from .names import md_dirs, md_names
from .reading import Analysis

_REF_KEYS = ("depends_on", "start_before", "start_on_ready", "members")
_KEY_RE = re.compile(r"\s*(?:add\s+)?([A-Za-z_][A-Za-z0-9_]*)\s*:")
_COND_RE = re.compile(r"\s*if(n)?def\s+[^:]*\Z")
K = lsp.CompletionItemKind


def complete(analysis: Analysis, path: str, text: str, line: int, character: int,
             extra_md_dirs: list[Path]) -> list[lsp.CompletionItem]:
    lines = text.split("\n")
    before = lines[line][:character] if line < len(lines) else ""
    parser = analysis.parser
    if _in_call(before) or _COND_RE.match(before):
        names = list(parser.evaluator.defines) if parser else []
        return (_items(names, K.Variable, "define")
                + _items([*CONTEXT_BUILTINS, *GLOBAL_BUILTINS], K.Constant, "builtin")
                + _items(FUNCTIONS, K.Function, "function"))
    header = section_at(analysis, path, line)
    section = header.word if header else ""
    key = _KEY_RE.match(before)
    if key is None:
        return (_items(SECTION_KEYS.get(section, ()), K.Property, f"{section} key")
                + _items(TOP_WORDS, K.Keyword, "section or directive"))
    word = re.split(r"[\s,]", before)[-1]
    return _values(analysis, key.group(1), section, word, extra_md_dirs)


def _values(analysis: Analysis, key: str, section: str, word: str,
            extra_md_dirs: list[Path]) -> list[lsp.CompletionItem]:
    parser = analysis.parser
    if parser is not None:
        d = parser.drafts
        if key in _REF_KEYS:
            return (_items(d.processes, K.Class, "process") + _items(d.states, K.Event, "state")
                    + _items(d.groups, K.Module, "group"))
        if key == "node":
            return _items([*d.hosts, *d.node_map], K.Interface, "host")
        if key == "use_template":
            return _items(parser.templates, K.Struct, "template")
    if key == "flags":
        return _items(sorted(GROUP_FLAGS if section == "group" else FLAGS), K.EnumMember, "flag")
    if "/" in word:
        return _items(md_names(md_dirs(analysis, extra_md_dirs)), K.File, "md")
    return []


def _in_call(before: str) -> bool:
    """Whether the cursor is right inside an unclosed `%(` (at its name)."""
    i = before.rfind("%(")
    return i >= 0 and ")" not in before[i:] and " " not in before[i + 2:].strip()


def _items(words, kind: lsp.CompletionItemKind, detail: str) -> list[lsp.CompletionItem]:
    return [lsp.CompletionItem(label=w, kind=kind, detail=detail) for w in dict.fromkeys(words)]
