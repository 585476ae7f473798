"""The outline of a `.lnc` file: its sections (processes, states, groups, templates,
networks, loggers, the instance) with hosts and defines under their sections, each from
the header the reader met, spanning to the next header."""

from __future__ import annotations

from lsprotocol import types as lsp

from .locations import token_range
from .reading import Analysis

S = lsp.SymbolKind
_KINDS = {"process": S.Class, "state": S.Event, "group": S.Module, "template": S.Struct,
          "process_template": S.Struct, "network": S.Namespace, "logger": S.Object,
          "instance": S.Package, "hosts": S.Namespace, "defines": S.Namespace,
          "node_map": S.Namespace, "topics": S.Namespace}


def document_symbols(analysis: Analysis, path: str, lines: list[str]
                     ) -> list[lsp.DocumentSymbol]:
    headers = sorted({h.loc.line: h for h in analysis.records.headers
                      if h.loc.file == path}.values(), key=lambda h: h.loc.line)
    parser = analysis.parser
    out = []
    for i, h in enumerate(headers):
        last = (headers[i + 1].loc.line - 1 if i + 1 < len(headers) else len(lines)) - 1
        last = max(last, h.loc.line - 1)
        end = len(lines[last]) if last < len(lines) else 0
        span = lsp.Range(lsp.Position(h.loc.line - 1, 0), lsp.Position(last, end))
        name = h.text[len(h.word):].strip()
        children = []
        if parser is not None and h.word == "hosts":
            children = [_leaf(n, S.Interface, host.location, lines, "host")
                        for n, host in parser.drafts.hosts.items()
                        if host.location.file == path and h.loc.line < host.location.line <= last + 1]
        elif h.word == "defines":
            children = [_leaf(s.name, S.Constant, s.loc, lines, s.value)
                        for s in analysis.records.defines
                        if s.loc.file == path and h.loc.line < s.loc.line <= last + 1]
        out.append(lsp.DocumentSymbol(name=f"{h.word} {name}".strip(), detail=h.word,
                                      kind=_KINDS.get(h.word, S.Namespace), range=span,
                                      selection_range=token_range(h.loc, lines, len(h.word)),
                                      children=list({c.name: c for c in children}.values())))
    return out


def _leaf(name: str, kind: lsp.SymbolKind, loc, lines: list[str], detail: str
          ) -> lsp.DocumentSymbol:
    r = token_range(loc, lines, len(name))
    return lsp.DocumentSymbol(name=name, kind=kind, range=r, selection_range=r, detail=detail)
