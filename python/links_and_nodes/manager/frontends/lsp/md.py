"""Message definition files in the editor, through ln_generate's own parser and lookup:
diagnostics (its syntax errors and warnings, and what resolving it finds: imports not
found, unknown field types; md_check.py), the outline (sections, fields, defines) and go
to definition of imported md names."""

from __future__ import annotations

import re
from pathlib import Path

from lsprotocol import types as lsp

from ln_generate.diagnostics import Diagnostic, Location, MdError
from ln_generate.lookup import LookupError_, default_md_dirs, find
from ln_generate.parser import RawFile, parse

from .md_check import check, home

SOURCE = "ln_generate"
_NAME_RE = re.compile(r"[A-Za-z0-9_/]+|\S+")


def read(text: str, path: str) -> tuple[RawFile | None, list[Diagnostic]]:
    """The syntax tree and every problem; None for a text that is not UTF-8."""
    try:
        raw = parse(text.encode("utf-8", "surrogatepass"), path)
    except MdError as exc:
        return None, exc.diagnostics
    return raw, [*raw.errors, *raw.warnings]


def resolve_define(path: str, md_name: str, dirs: list[Path]) -> Path:
    """The file of an imported md name (first beside the importing md, as ln_generate
    looks); raises LookupError_ when it is not found."""
    all_dirs = default_md_dirs([str(d) for d in dirs])
    return find(md_name, all_dirs, home(path, all_dirs))[2]


def diagnostics(text: str, path: str, dirs: list[Path]) -> list[lsp.Diagnostic]:
    raw, found = read(text, path)
    if raw is not None:
        found += check(raw, path, dirs)
    return [_diagnostic(d, len(_word(text, d.loc))) for d in found]


def _word(text: str, loc: Location) -> str:
    lines = text.split("\n")
    line = lines[loc.line - 1] if 0 < loc.line <= len(lines) else ""
    m = _NAME_RE.match(line, loc.col - 1)
    return m.group() if m else " "


def _range(loc: Location, length: int) -> lsp.Range:
    start = lsp.Position(loc.line - 1, loc.col - 1)
    return lsp.Range(start, lsp.Position(loc.line - 1, loc.col - 1 + max(length, 1)))


def _diagnostic(d: Diagnostic, length: int) -> lsp.Diagnostic:
    severity = (lsp.DiagnosticSeverity.Warning if d.severity == "warning"
                else lsp.DiagnosticSeverity.Error)
    return lsp.Diagnostic(range=_range(d.loc, length), message=d.message, severity=severity,
                          source=SOURCE)


def symbols(text: str, path: str) -> list[lsp.DocumentSymbol]:
    raw, _ = read(text, path)
    if raw is None:
        return []
    S = lsp.SymbolKind
    out = [lsp.DocumentSymbol(name=d.alias, kind=S.TypeParameter, detail=d.md_name,
                              range=_range(d.alias_loc, len(d.alias)),
                              selection_range=_range(d.alias_loc, len(d.alias)))
           for d in raw.defines]
    for section in raw.sections:
        fields = [lsp.DocumentSymbol(
            name=f.name, kind=S.Field,
            detail=f"{f.type_name}{'*' if f.dynamic else ''}"
                   f"{f'[{f.count}]' if f.count else ''}",
            range=_range(f.type_loc, f.name_loc.col - f.type_loc.col + len(f.name)),
            selection_range=_range(f.name_loc, len(f.name))) for f in section.fields]
        if not section.name:
            out += fields
            continue
        last = fields[-1].range.end if fields else _range(section.loc, len(section.name)).end
        out.append(lsp.DocumentSymbol(
            name=section.name, kind=S.Namespace, children=fields,
            range=lsp.Range(_range(section.loc, 1).start, last),
            selection_range=_range(section.loc, len(section.name))))
    return out


def definition(text: str, path: str, line: int, character: int, dirs: list[Path]
               ) -> Path | None:
    """The md file of the imported name (or of the local type name) under the cursor."""
    raw, _ = read(text, path)
    if raw is None:
        return None
    for d in raw.defines:
        on_name = d.name_loc.line == line + 1 and \
            d.name_loc.col - 1 <= character <= d.name_loc.col - 1 + len(d.md_name)
        on_alias = any(f.type_name == d.alias and f.type_loc.line == line + 1
                       and f.type_loc.col - 1 <= character <= f.type_loc.col - 1 + len(d.alias)
                       for s in raw.sections for f in s.fields)
        on_alias = on_alias or (d.alias_loc.line == line + 1 and
                                d.alias_loc.col - 1 <= character <= d.alias_loc.col - 1
                                + len(d.alias))
        if on_name or on_alias:
            try:
                return resolve_define(path, d.md_name, dirs)
            except LookupError_:
                return None
    return None
