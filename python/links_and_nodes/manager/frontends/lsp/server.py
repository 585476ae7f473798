"""`ln_lsp`: the language server for `.lnc` configurations and md files, on pygls.  Each
open configuration is read as a main file by the project's reader (reading.py) in a worker
thread, so a slow `%(shell)` or `pipe_include` (bounded by the shell-timeout setting)
delays only its own diagnostics; requests are answered from the newest read.  Positions
are converted at this edge between characters and the client's position encoding."""

from __future__ import annotations

import asyncio
import os
from concurrent.futures import ThreadPoolExecutor
from typing import Any

from lsprotocol import types as lsp
from pygls.lsp.server import LanguageServer

from .... import __version__
from ...config.model import Location
from . import completion, definitions, hover, md, symbols
from .diagnostics import add_include_summaries, diagnostics
from .documents import LNC, MD, kind_of
from .encoding import (
    diagnostics_to_client,
    position_from_client,
    range_to_client,
    symbols_to_client,
)
from .locations import path_to_uri, to_location, uri_to_path
from .names import MD as MD_TARGET
from .names import target_at
from .reading import Analysis, analyse
from .settings import Settings


class LnServer(LanguageServer):
    def __init__(self) -> None:
        super().__init__("ln_lsp", __version__)
        self.settings = Settings()
        self.kinds: dict[str, str] = {}  # path of an open document -> LNC or MD
        self.analyses: dict[str, Analysis] = {}  # open configuration -> its newest read
        self.tasks: dict[str, asyncio.Task[None]] = {}
        self.dirty: set[str] = set()
        self.executor = ThreadPoolExecutor(max_workers=2, thread_name_prefix="ln_lsp")

    # ---------------------------------------------------------------- documents

    def text(self, path: str) -> str:
        return self.workspace.get_text_document(path_to_uri(path)).source

    def lines(self, path: str) -> list[str]:
        if path in self.kinds:
            return self.text(path).split("\n")
        for a in self.analyses.values():
            if path in a.records.texts:
                return a.records.texts[path].split("\n")
        return []

    def is_open(self, path: str) -> bool:
        return os.path.abspath(path) in {os.path.abspath(p) for p in self.kinds}

    def position(self, path: str, pos: lsp.Position) -> lsp.Position:
        """A position the client sent, in characters."""
        return position_from_client(self.workspace.position_codec, self.lines(path), pos)

    def location(self, loc: Location, length: int | None) -> lsp.Location:
        """A place in characters, as the client counts."""
        lines = self.lines(loc.file)
        out = to_location(loc, lines, length)
        out.range = range_to_client(self.workspace.position_codec, lines, out.range)
        return out

    def owner(self, path: str) -> str:
        """The open configuration whose read speaks for `path`: one that includes it (it
        knows the defines and sections an include file is read in), else itself."""
        for main, a in self.analyses.items():
            if main != path and main in self.kinds and path in a.files:
                return main
        return path

    def opened(self, path: str, language_id: str | None) -> None:
        kind = kind_of(path, language_id)
        if kind is not None:
            self.kinds[path] = kind
        self.changed(path)

    def changed(self, path: str) -> None:
        kind = self.kinds.get(path)
        if kind == MD:
            doc = self.workspace.get_text_document(path_to_uri(path))
            self.publish(path, md.diagnostics(doc.source, path, self.settings.md_dirs),
                         doc.version)
        elif kind == LNC:
            self.schedule(path)
            for main, a in list(self.analyses.items()):
                if main != path and path in a.files:
                    self.schedule(main)

    def closed(self, path: str) -> None:
        self.kinds.pop(path, None)
        self.analyses.pop(path, None)
        self.publish(path, [])
        for main in list(self.analyses):
            self.schedule(main)

    # ---------------------------------------------------------------- reading

    def schedule(self, path: str) -> None:
        task = self.tasks.get(path)
        if task is not None and not task.done():
            self.dirty.add(path)
            return
        self.tasks[path] = asyncio.get_running_loop().create_task(self._read(path))

    async def _read(self, path: str) -> None:
        loop = asyncio.get_running_loop()
        while path in self.kinds:
            self.dirty.discard(path)
            doc = self.workspace.get_text_document(path_to_uri(path))
            text, version = doc.source, doc.version
            versions = {p: self.workspace.get_text_document(path_to_uri(p)).version
                        for p in self.kinds}
            versions[path] = version
            buffers = {os.path.realpath(p): self.text(p) for p, k in self.kinds.items()
                       if k == LNC and p != path}
            analysis = await loop.run_in_executor(self.executor, analyse, path, text,
                                                  self.settings, buffers)
            if path not in self.kinds:
                return
            self.analyses[path] = analysis
            if path not in self.dirty:
                self._publish_read(path, analysis, versions)
                return

    def _publish_read(self, main: str, analysis: Analysis,
                      versions: dict[str, int | None]) -> None:
        """The diagnostics of every open file this read speaks for, each with the version
        of the text that was read."""
        found = diagnostics(analysis, self.lines)
        add_include_summaries(analysis, found, self.is_open, self.lines)
        for path, items in found.items():
            if path in self.kinds and self.owner(path) == main:
                self.publish(path, items, versions.get(path))

    def publish(self, path: str, items: list[lsp.Diagnostic],
                version: int | None = None) -> None:
        items = diagnostics_to_client(self.workspace.position_codec, self.lines(path), items)
        self.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(
            uri=path_to_uri(path), diagnostics=items, version=version))

    async def analysis(self, path: str) -> Analysis | None:
        """The newest read that speaks for `path`, waiting for the first one."""
        main = self.owner(path)
        if main not in self.analyses and main in self.tasks:
            await asyncio.shield(self.tasks[main])
        return self.analyses.get(main)

    def configure(self, data: Any) -> None:
        self.settings = Settings.from_json(data)
        for problem in self.settings.problems:
            self.window_show_message(lsp.ShowMessageParams(lsp.MessageType.Warning,
                                                           f"ln_lsp settings: {problem}"))


server = LnServer()


@server.feature(lsp.INITIALIZE)
def _initialize(ls: LnServer, params: lsp.InitializeParams) -> None:
    ls.configure(params.initialization_options)


@server.feature(lsp.WORKSPACE_DID_CHANGE_CONFIGURATION)
def _configuration(ls: LnServer, params: lsp.DidChangeConfigurationParams) -> None:
    ls.configure(params.settings)
    for path in list(ls.kinds):
        ls.changed(path)


@server.feature(lsp.TEXT_DOCUMENT_DID_OPEN)
def _did_open(ls: LnServer, params: lsp.DidOpenTextDocumentParams) -> None:
    ls.opened(uri_to_path(params.text_document.uri), params.text_document.language_id)


@server.feature(lsp.TEXT_DOCUMENT_DID_CHANGE)
def _did_change(ls: LnServer, params: lsp.DidChangeTextDocumentParams) -> None:
    ls.changed(uri_to_path(params.text_document.uri))


@server.feature(lsp.TEXT_DOCUMENT_DID_CLOSE)
def _did_close(ls: LnServer, params: lsp.DidCloseTextDocumentParams) -> None:
    ls.closed(uri_to_path(params.text_document.uri))


@server.feature(lsp.TEXT_DOCUMENT_HOVER)
async def _hover(ls: LnServer, params: lsp.HoverParams) -> lsp.Hover | None:
    path = uri_to_path(params.text_document.uri)
    analysis = await ls.analysis(path)
    if ls.kinds.get(path) != LNC or analysis is None:
        return None
    pos = ls.position(path, params.position)
    found = hover.hover_text(analysis, path, ls.text(path), pos.line, pos.character,
                             ls.settings.md_dirs)
    if found is None:
        return None
    text, where = found
    return lsp.Hover(lsp.MarkupContent(lsp.MarkupKind.Markdown, text),
                     range_to_client(ls.workspace.position_codec, ls.lines(path), where))


@server.feature(lsp.TEXT_DOCUMENT_DEFINITION)
async def _definition(ls: LnServer, params: lsp.DefinitionParams) -> list[lsp.Location]:
    path = uri_to_path(params.text_document.uri)
    pos = ls.position(path, params.position)
    if ls.kinds.get(path) == MD:
        found = md.definition(ls.text(path), path, pos.line, pos.character,
                              ls.settings.md_dirs)
        return [lsp.Location(path_to_uri(str(found)), lsp.Range(lsp.Position(0, 0),
                                                                 lsp.Position(0, 0)))] \
            if found else []
    analysis = await ls.analysis(path)
    if analysis is None:
        return []
    found_target = target_at(analysis, path, ls.text(path), pos.line, pos.character,
                             ls.settings.md_dirs)
    if found_target is None:
        return []
    sites = definitions.definition(analysis, found_target[0])
    return [ls.location(loc, length) for loc, length in sites]


@server.feature(lsp.TEXT_DOCUMENT_REFERENCES)
async def _references(ls: LnServer, params: lsp.ReferenceParams) -> list[lsp.Location]:
    path = uri_to_path(params.text_document.uri)
    analysis = await ls.analysis(path)
    if ls.kinds.get(path) != LNC or analysis is None:
        return []
    pos = ls.position(path, params.position)
    found = target_at(analysis, path, ls.text(path), pos.line, pos.character,
                      ls.settings.md_dirs)
    if found is None or found[0].kind == MD_TARGET:
        return []
    sites = definitions.references(analysis, found[0], params.context.include_declaration)
    return [ls.location(loc, length) for loc, length in sites]


@server.feature(lsp.TEXT_DOCUMENT_COMPLETION,
                lsp.CompletionOptions(trigger_characters=["(", ":", " ", ",", "/"]))
async def _completion(ls: LnServer, params: lsp.CompletionParams) -> lsp.CompletionList:
    path = uri_to_path(params.text_document.uri)
    analysis = await ls.analysis(path)
    if ls.kinds.get(path) != LNC or analysis is None:
        return lsp.CompletionList(is_incomplete=False, items=[])
    pos = ls.position(path, params.position)
    items = completion.complete(analysis, path, ls.text(path), pos.line, pos.character,
                                ls.settings.md_dirs)
    return lsp.CompletionList(is_incomplete=False, items=items)


@server.feature(lsp.TEXT_DOCUMENT_DOCUMENT_SYMBOL)
async def _symbols(ls: LnServer, params: lsp.DocumentSymbolParams
                   ) -> list[lsp.DocumentSymbol]:
    path = uri_to_path(params.text_document.uri)
    codec, lines = ls.workspace.position_codec, ls.lines(path)
    if ls.kinds.get(path) == MD:
        return symbols_to_client(codec, lines, md.symbols(ls.text(path), path))
    analysis = await ls.analysis(path)
    if analysis is None:
        return []
    return symbols_to_client(codec, lines, symbols.document_symbols(analysis, path, lines))


def main() -> None:
    server.start_io()
