"""The problems of a read as LSP diagnostics, per file: the texts `ln_manager check`
prints (errors, and warnings with `--strict` off), each at its `file:line:col`; and, on an
open file, a summary of each included file that is not open but has problems."""

from __future__ import annotations

import os
from collections.abc import Callable

from lsprotocol import types as lsp

from ...config.errors import relative
from ...config.model import Location
from .locations import real_place, token_range
from .reading import Analysis

SOURCE = "ln_manager check"
Site = tuple[Location, int | None]  # an include's argument and its length (None: the word)


def diagnostics(analysis: Analysis, lines_of: Callable[[str], list[str]]
                ) -> dict[str, list[lsp.Diagnostic]]:
    """file -> its diagnostics; every file the read touched has an entry (maybe empty),
    so that fixed problems disappear."""
    out: dict[str, list[lsp.Diagnostic]] = {f: [] for f in analysis.files
                                            if not f.endswith(": output of pipe_include")}
    out.setdefault(analysis.path, [])
    for problems, severity in ((analysis.errors, lsp.DiagnosticSeverity.Error),
                               (analysis.warnings, lsp.DiagnosticSeverity.Warning)):
        for p in problems:
            loc, note = real_place(p.location)
            out.setdefault(loc.file, []).append(lsp.Diagnostic(
                range=token_range(loc, lines_of(loc.file)), message=p.message + note,
                severity=severity, source=SOURCE))
    return out


def add_include_summaries(analysis: Analysis, found: dict[str, list[lsp.Diagnostic]],
                          is_open: Callable[[str], bool],
                          lines_of: Callable[[str], list[str]]) -> None:
    """For each file of `found` that has problems and is not open: one diagnostic on the
    open file that includes it (directly or through other files that are not open), at
    the argument of the include that leads there, with the worst severity of them."""
    parents: dict[str, Site] = {}
    for site in analysis.records.includes:
        at, note = real_place(site.loc)
        parents.setdefault(os.path.abspath(site.target),
                           (at, site.length if site.length and not note else None))
    root = os.path.dirname(analysis.path)
    for file, items in list(found.items()):
        if not items or is_open(file):
            continue
        site = _open_site(os.path.abspath(file), parents, is_open)
        if site is None:
            continue
        at, length = site
        found.setdefault(at.file, []).append(lsp.Diagnostic(
            range=token_range(at, lines_of(at.file), length),
            message=_summary(relative(file, root), items),
            severity=min(d.severity or lsp.DiagnosticSeverity.Error for d in items),
            source=SOURCE))


def _open_site(file: str, parents: dict[str, Site], is_open: Callable[[str], bool]
               ) -> Site | None:
    """The include in an open file that leads to `file`, following the chain up."""
    seen: set[str] = set()
    while file in parents and file not in seen:
        seen.add(file)
        site = parents[file]
        if is_open(site[0].file):
            return site
        file = os.path.abspath(site[0].file)
    return None


def _summary(name: str, items: list[lsp.Diagnostic]) -> str:
    first = min(items, key=lambda d: (d.range.start.line, d.range.start.character))
    start = first.range.start
    count = f"{len(items)} problem{'s' if len(items) != 1 else ''}"
    return (f"included file '{name}' has {count}; the first: "
            f"{name}:{start.line + 1}:{start.character + 1}: {first.message}")
