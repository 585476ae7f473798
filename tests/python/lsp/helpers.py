"""Talking to the server in tests: open or change a document and wait for its
diagnostics, and the places of the answers."""

from __future__ import annotations

import asyncio
from pathlib import Path

from lsprotocol import types as lsp
from pytest_lsp import LanguageClient

REPO = Path(__file__).resolve().parents[3]
CORPUS = REPO.parent / "shared" / "real_ln"
WAIT = 30.0  # seconds: a bound against a hang, never a measure


async def diagnostics_for(client: LanguageClient, uri: str, version: int, start: int
                          ) -> list[lsp.Diagnostic]:
    """Wait for diagnostics of `uri` at `version` published after the first `start`."""
    async def wait() -> list[lsp.Diagnostic]:
        while True:
            for params in client.published[start:]:
                if params.uri == uri and params.version == version:
                    return list(params.diagnostics)
            await asyncio.sleep(0.01)
    return await asyncio.wait_for(wait(), WAIT)


async def open_doc(client: LanguageClient, path: Path, text: str | None = None,
                   language: str = "lnc", wait: bool = True) -> list[lsp.Diagnostic]:
    uri = path.as_uri()
    start = len(client.published)
    client.text_document_did_open(lsp.DidOpenTextDocumentParams(lsp.TextDocumentItem(
        uri=uri, language_id=language, version=1,
        text=path.read_text() if text is None else text)))
    return await diagnostics_for(client, uri, 1, start) if wait else []


async def change_doc(client: LanguageClient, path: Path, text: str, version: int
                     ) -> list[lsp.Diagnostic]:
    uri = path.as_uri()
    start = len(client.published)
    client.text_document_did_change(lsp.DidChangeTextDocumentParams(
        lsp.VersionedTextDocumentIdentifier(version=version, uri=uri),
        [lsp.TextDocumentContentChangeWholeDocument(text=text)]))
    return await diagnostics_for(client, uri, version, start)


def pos(path: Path, line: int, character: int) -> dict:
    """Arguments of a position request (0-based line and character)."""
    return {"text_document": lsp.TextDocumentIdentifier(uri=path.as_uri()),
            "position": lsp.Position(line, character)}


def where(location: lsp.Location) -> tuple[str, int, int, int]:
    """(file name, line, first and last character) of a location, 0-based."""
    r = location.range
    assert r.start.line == r.end.line
    return Path(location.uri.removeprefix("file://")).name, r.start.line, r.start.character, \
        r.end.character
