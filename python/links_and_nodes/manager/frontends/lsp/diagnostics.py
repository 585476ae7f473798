"""The problems of a read as LSP diagnostics, per file: the texts `ln_manager check`
prints (errors, and warnings with `--strict` off), each at its `file:line:col`."""

from __future__ import annotations

from collections.abc import Callable

from lsprotocol import types as lsp

from .locations import real_place, token_range
from .reading import Analysis

SOURCE = "ln_manager check"


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
