"""ln_lsp's positions in the encoding agreed with the client: UTF-16 code units by
default, UTF-32 or UTF-8 when the client offers them first.  A line holding a character
outside the Basic Multilingual Plane (an emoji: 2 UTF-16 units, 4 UTF-8 bytes) shifts every
column after it; diagnostics, hover, definition, references, completion and the outline
must all agree with the client's count."""

from __future__ import annotations

from pathlib import Path

import pytest
from lsprotocol import types as lsp

from .helpers import open_doc

LINE = 'command: echo "\U0001f600" %(base) %(nosuch)  # \U0001f389'
TEXT = f"""instance
name: t
manager: :54999
defines
base: /opt/robot
process arm
{LINE}
process viewer
command: viewer
"""
ROW = 6  # the line of LINE


def units(text: str, encoding: str) -> int:
    """How many units of `encoding` the client counts in `text` (independent of pygls)."""
    if encoding == "utf-8":
        return len(text.encode("utf-8"))
    if encoding == "utf-16":
        return len(text.encode("utf-16-le")) // 2
    return len(text)


@pytest.mark.parametrize("offered,chosen", [
    (None, "utf-16"),  # VS Code 1.65 offers none: LSP's default
    (["utf-32", "utf-16"], "utf-32"),
    (["utf-8", "utf-16"], "utf-8"),
])
async def test_positions_follow_the_agreed_encoding(start_server, tmp_path: Path,
                                                    offered, chosen):
    server = await start_server(encodings=offered)
    assert server.position_encoding == chosen
    path = tmp_path / "emoji.lnc"

    def col(characters: int) -> int:  # a column of LINE, as this client counts
        return units(LINE[:characters], chosen)

    def where(line: int, character: int) -> dict:
        return {"text_document": lsp.TextDocumentIdentifier(uri=path.as_uri()),
                "position": lsp.Position(line, character)}

    bad = LINE.index("%(nosuch)")
    [d] = await open_doc(server, path, TEXT)
    assert "'nosuch'" in d.message
    assert (d.range.start.line, d.range.start.character, d.range.end.character) == \
        (ROW, col(bad), col(bad + len("%(nosuch)")))

    base = LINE.index("base)")
    hover = await server.text_document_hover_async(lsp.HoverParams(**where(ROW, col(base) + 1)))
    assert "/opt/robot" in hover.contents.value
    assert (hover.range.start.character, hover.range.end.character) == \
        (col(base), col(base + 4))

    found = await server.text_document_definition_async(
        lsp.DefinitionParams(**where(ROW, col(base))))
    assert [(x.range.start.line, x.range.start.character) for x in found] == [(4, 0)]
    refs = await server.text_document_references_async(lsp.ReferenceParams(
        context=lsp.ReferenceContext(include_declaration=False), **where(4, 1)))
    assert [(r.range.start.line, r.range.start.character, r.range.end.character)
            for r in refs] == [(ROW, col(base), col(base + 4))]

    # right before the ')' of %(base): inside the call, so define names; one character
    # further (what a wrong count would take) the call is closed
    inside = await server.text_document_completion_async(
        lsp.CompletionParams(**where(ROW, col(base + 4))))
    assert "base" in {i.label for i in inside.items}
    after = await server.text_document_completion_async(
        lsp.CompletionParams(**where(ROW, col(base + 5))))
    assert "base" not in {i.label for i in after.items}

    outline = await server.text_document_document_symbol_async(
        lsp.DocumentSymbolParams(lsp.TextDocumentIdentifier(path.as_uri())))
    [process] = [s for s in outline if s.name == "process arm"]
    assert (process.range.end.line, process.range.end.character) == (ROW, col(len(LINE)))
