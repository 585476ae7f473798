"""ln_lsp on message definitions (ln_generate's parser: diagnostics, outline, definition
of imported md names) and on the real files of ../shared/real_ln, read in place."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from lsprotocol import types as lsp

from .helpers import CORPUS, open_doc, pos, where

if not CORPUS.is_dir():
    if os.environ.get("CI"):
        pytest.fail(f"the real_ln corpus {CORPUS} is missing (CI=1: this is a failure)",
                    pytrace=False)
    pytest.skip(f"the real_ln corpus {CORPUS} is not here", allow_module_level=True)

MD_SET = CORPUS / "md" / "ln_helper_generated"
AREAS = MD_SET / "service_provider_memory_inspection" / "get_memory_areas"
RK = CORPUS / "lnc" / "robotkernel" / "robotkernel.inc.lnc"


async def test_real_md_outline_and_definition(start_server):
    server = await start_server({"mdDirs": [str(MD_SET)]})
    assert await open_doc(server, AREAS, language="lnmd") == []
    found = await server.text_document_document_symbol_async(
        lsp.DocumentSymbolParams(lsp.TextDocumentIdentifier(AREAS.as_uri())))
    assert [(s.name, s.kind) for s in found] == [
        ("memory_area", lsp.SymbolKind.TypeParameter), ("request", lsp.SymbolKind.Namespace),
        ("response", lsp.SymbolKind.Namespace)]
    assert [(c.name, c.detail) for c in found[2].children] == [
        ("areas", "memory_area*"), ("error_message", "char*")]
    target = await server.text_document_definition_async(
        lsp.DefinitionParams(**pos(AREAS, 4, 30)))  # "service_provider_.../memory_area"
    assert [where(t) for t in target] == [("memory_area", 0, 0, 0)]
    assert Path(target[0].uri.removeprefix("file://")).parent.name == \
        "service_provider_memory_inspection"
    target = await server.text_document_definition_async(
        lsp.DefinitionParams(**pos(AREAS, 5, 3)))  # the field's type: the local name
    assert [where(t) for t in target] == [("memory_area", 0, 0, 0)]


async def test_md_syntax_errors_and_missing_imports(start_server, tmp_path: Path):
    server = await start_server({"mdDirs": [str(tmp_path)]})
    path = tmp_path / "robot" / "pose"
    path.parent.mkdir()
    found = await open_doc(server, path, 'define x as "robot/none"\nx a\ndouble b[2*]\n',
                           language="lnmd")
    assert [(d.range.start.line, d.range.start.character) for d in found] == [(2, 11), (0, 13)]
    assert found[0].message == "incomplete array size expression"
    assert found[1].message.startswith("message definition 'robot/none' not found")


async def test_real_include_file_from_a_main_file(server, tmp_path: Path):
    """robotkernel.inc.lnc, included in place from a small main file (as
    test_lnc_real_world.py checks it): its warning is summarised on the include line while
    it is not open and shown in it once it is; hover and outline."""
    main = tmp_path / "main.lnc"
    main.write_text(f"instance\nname: rk\nmanager: :54414\ninclude {RK}\n")
    [summary] = await open_doc(server, main)
    assert (summary.range.start.line, summary.range.start.character) == (3, 8)
    assert summary.severity == lsp.DiagnosticSeverity.Warning
    assert summary.message.startswith(f"included file '{RK}' has 1 problem; the first: "
                                      f"{RK}:50:")
    found = await open_doc(server, RK)
    assert [(d.range.start.line, d.severity, d.message) for d in found] == [
        (49, lsp.DiagnosticSeverity.Warning,
         f"message definition directory '{CORPUS / 'share' / 'ln' / 'message_definitions'}'"
         " not found (ignored)")]
    hover = await server.text_document_hover_async(lsp.HoverParams(**pos(RK, 51, 10)))
    assert f"{CORPUS}/bin/$(ARCH)/robotkernel" in hover.contents.value
    symbols = await server.text_document_document_symbol_async(
        lsp.DocumentSymbolParams(lsp.TextDocumentIdentifier(RK.as_uri())))
    assert [s.name for s in symbols] == ["defines", 'process %(ifndef "rk_name", "robotkernel")']
    assert "rk_binary" in [c.name for c in symbols[0].children]
    target = await server.text_document_definition_async(
        lsp.DefinitionParams(**pos(RK, 52, 33)))  # %(rk_binary) in command
    assert [where(t) for t in target] == [("robotkernel.inc.lnc", 46, 0, 9)]
