"""Hover in `.lnc` files: a keyword's documentation (keywords.py), a define's value, a
process's resolved command, a template's parameters, a host's interfaces, an md file;
each with the range (in characters) of the name or word it is about."""

from __future__ import annotations

from pathlib import Path

from lsprotocol import types as lsp

from .keywords import describe, section_at
from .locations import token_range, word_at
from .names import DEFINE, FILE, HOST, MD, NAME, TEMPLATE, Target, target_at
from .reading import Analysis


def hover_text(analysis: Analysis, path: str, text: str, line: int, character: int,
               md_dirs: list[Path]) -> tuple[str, lsp.Range] | None:
    found = target_at(analysis, path, text, line, character, md_dirs)
    if found is not None:
        described = _describe_target(analysis, found[0])
        if described:
            return described, token_range(found[1], text.split("\n"), found[2] or None)
    word, start = word_at(text, line, character)
    if not word:
        return None
    header = section_at(analysis, path, line)
    section = header.word if header else ""
    before = text.split("\n")[line][:start]
    in_flags = "flags" in before and ":" in before
    described = describe(word, section if before.strip() or header is None or
                         header.loc.line != line + 1 else "", in_flags)
    if described is None:
        return None
    return described, lsp.Range(lsp.Position(line, start), lsp.Position(line, start + len(word)))


def _describe_target(analysis: Analysis, target: Target) -> str | None:
    parser = analysis.parser
    if target.kind in (FILE, MD):
        return f"{'md file' if target.kind == MD else 'file'} `{target.name}`"
    if parser is None:
        return None
    d = parser.drafts
    if target.kind == DEFINE:
        value = parser.evaluator.defines.get(target.name)
        if value is None:
            return f"define `{target.name}`: not defined at the end of the files"
        given = " (given in the settings, as -D)" if target.name in parser.evaluator.fixed else ""
        return f"define `{target.name}`{given}\n\n```\n{value}\n```"
    if target.kind == TEMPLATE and target.name in parser.templates:
        return f"template `{parser.templates[target.name].usage()}`"
    if target.kind == HOST and target.name in d.hosts:
        host = d.hosts[target.name]
        ifaces = ", ".join(f"{k}: {v}" for k, v in host.interfaces.items()) or "no interfaces"
        return f"host `{host.name}`: {ifaces}"
    if target.kind != NAME:
        return None
    if target.name in d.processes:
        p = d.processes[target.name].process
        deps = f"\n\ndepends on: {', '.join(r.text for r in d.processes[target.name].refs['depends_on'])}" \
            if d.processes[target.name].refs["depends_on"] else ""
        return f"process `{p.name}` on `{p.node}`\n\n```sh\n{p.command}\n```{deps}"
    if target.name in d.states:
        s = d.states[target.name].state
        return f"state `{s.name}`\n\ncheck:\n```sh\n{s.check}\n```"
    if target.name in d.groups:
        members = ", ".join(r.text for r in d.groups[target.name].members)
        return f"group `{target.name}`: {members or 'no members'}"
    return None
