"""What a read of a configuration names and where: processes, states, groups, templates,
hosts, defines, includes and md names, and which of them lies under the cursor.  Built from
what the reader collected (its drafts, templates and references), never by reading the
language again; only `%(NAME)` uses are found in the text itself."""

from __future__ import annotations

import os
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from ln_generate.lookup import check_name, default_md_dirs

from ...config.drafts import Ref
from ...config.model import Location
from .locations import covers, word_at
from .reading import Analysis

NAME = "name"  # a process, state or group: one name space
TEMPLATE = "template"
DEFINE = "define"
HOST = "host"
FILE = "file"
MD = "md"
_DEFINE_USE_RE = re.compile(r"%\(\s*([A-Za-z_][A-Za-z0-9_.\-/]*)\s*\)"
                            r"|%\((?:ifdef|ifndef)\s+\"?([A-Za-z_][A-Za-z0-9_.\-/]*)\"?")
MAX_MD_FILES = 5000


@dataclass(frozen=True)
class Target:
    kind: str
    name: str  # full name; for FILE and MD the path of the file


def all_refs(analysis: Analysis) -> Iterator[Ref]:
    parser = analysis.parser
    if parser is None:
        return
    for d in parser.drafts.processes.values():
        for refs in d.refs.values():
            yield from refs
    for g in parser.drafts.groups.values():
        yield from g.members


def resolve_ref(analysis: Analysis, ref: Ref) -> str | None:
    """The process, state or group a reference names, through the name prefixes in effect
    where it was written (as resolve.py finds it)."""
    parser = analysis.parser
    if parser is None:
        return None
    for scope in ref.scopes:
        full = f"{scope}/{ref.text}" if scope else ref.text
        if full in parser.names:
            return full
    return None


def name_locations(analysis: Analysis) -> dict[str, Location]:
    """Processes, states and groups -> the place of their name in the header."""
    parser = analysis.parser
    if parser is None:
        return {}
    d = parser.drafts
    out = {n: p.name_loc for n, p in d.processes.items()}
    out.update({n: s.name_loc for n, s in d.states.items()})
    out.update({n: g.name_loc for n, g in d.groups.items()})
    return out


def define_uses(text: str, file: str, name: str | None = None
                ) -> Iterator[tuple[str, Location, int]]:
    """`%(NAME)` and `%(ifdef "NAME"` uses in a text: (name, place, length)."""
    for number, line in enumerate(text.split("\n"), 1):
        if "%(" not in line:
            continue
        for m in _DEFINE_USE_RE.finditer(line):
            group = 1 if m.group(1) else 2
            if name is None or m.group(group) == name:
                yield m.group(group), Location(file, number, m.start(group) + 1), \
                    len(m.group(group))


def md_dirs(analysis: Analysis, extra: list[Path]) -> list[Path]:
    """Where md names are looked up: the settings' directories, the configuration's
    `add_message_definition_dir`s, then ln_generate's defaults."""
    parser = analysis.parser
    dirs = [Path(p) for p in parser.drafts.message_definition_dirs] if parser else []
    if parser:
        for d in parser.drafts.processes.values():
            dirs += [Path(p) for p in d.process.message_definition_dirs]
    return default_md_dirs([str(p) for p in [*extra, *dirs]])


def find_md(name: str, dirs: list[Path]) -> Path | None:
    if "/" not in name or check_name(name) is not None:
        return None
    for d in dirs:
        candidate = d / name
        if candidate.is_file() and candidate.resolve().is_relative_to(d.resolve()):
            return candidate
    return None


def md_names(dirs: list[Path]) -> list[str]:
    """The md names in `dirs` (files whose path components are identifiers)."""
    names: list[str] = []
    for d in dirs:
        for root, subdirs, files in os.walk(d):
            subdirs[:] = sorted(s for s in subdirs if not s.startswith("."))
            for f in sorted(files):
                name = os.path.relpath(os.path.join(root, f), d)
                if check_name(name) is None and name not in names:
                    names.append(name)
                if len(names) >= MAX_MD_FILES:
                    return names
    return names


def target_at(analysis: Analysis, path: str, text: str, line: int, character: int,
              extra_md_dirs: list[Path]) -> tuple[Target, Location, int] | None:
    """The named thing under the cursor: (what, where it is written, length)."""
    parser = analysis.parser
    if parser is not None:
        for ref in all_refs(analysis):
            if covers(ref.loc, len(ref.text), path, line, character):
                full = resolve_ref(analysis, ref)
                if full is not None:
                    return Target(NAME, full), ref.loc, len(ref.text)
        found = _declared_at(analysis, path, text, line, character)
        if found is not None:
            return found
    for name, loc, length in define_uses(text.split("\n")[line] if line < len(
            text.split("\n")) else "", path):
        if loc.col - 1 <= character <= loc.col - 1 + length:
            return Target(DEFINE, name), Location(path, line + 1, loc.col), length
    word, start = word_at(text, line, character)
    if word:
        md = find_md(word, md_dirs(analysis, extra_md_dirs))
        if md is not None:
            return Target(MD, str(md)), Location(path, line + 1, start + 1), len(word)
        if parser is not None and word in parser.drafts.hosts:
            return Target(HOST, word), Location(path, line + 1, start + 1), len(word)
    return None


def _declared_at(analysis: Analysis, path: str, text: str, line: int, character: int
                 ) -> tuple[Target, Location, int] | None:
    """A name where it is declared or used by the reader's own records."""
    parser = analysis.parser
    assert parser is not None
    records = analysis.records
    for site in records.includes:
        if covers(site.loc, site.length or 10_000, path, line, character):
            return Target(FILE, site.target), site.loc, site.length
    for use in records.template_uses:
        if covers(use.loc, len(use.name), path, line, character):
            return Target(TEMPLATE, use.template.name), use.loc, len(use.name)
    for name, template in parser.templates.items():
        if covers(template.loc, len(name.rsplit("/", 1)[-1]), path, line, character):
            return Target(TEMPLATE, name), template.loc, len(name.rsplit("/", 1)[-1])
    for name, loc in name_locations(analysis).items():
        if loc.file == path and loc.line == line + 1 and character >= loc.col - 1:
            return Target(NAME, name), loc, len(name.rsplit("/", 1)[-1])
    for site in records.defines:
        if covers(site.loc, len(site.name), path, line, character):
            return Target(DEFINE, site.name), site.loc, len(site.name)
    for name, host in parser.drafts.hosts.items():
        if covers(host.location, len(name), path, line, character):
            return Target(HOST, name), host.location, len(name)
    return None
