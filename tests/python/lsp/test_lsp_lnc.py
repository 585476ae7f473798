"""ln_lsp on `.lnc` files, end to end over stdio: diagnostics as `ln_manager check` words
them (unsaved text, --strict, -D, includes of open buffers), hover, definition,
references, completion and the outline, at exact positions of a hand-written file."""

from __future__ import annotations

from pathlib import Path

from lsprotocol import types as lsp

from .helpers import change_doc, open_doc, pos, where

ROBOT = """instance
name: t
manager: :54999
defines
base: /opt/robot
hosts
robot: eth0:10.0.0.2
template arm_tpl(side)
node: robot
command: %(base)/bin/arm %(side)
process arm
use_template: arm_tpl(left)
process viewer
depends_on: arm
command: viewer --base %(base)
group all
members: arm, viewer
"""


async def test_unsaved_text_gives_check_diagnostics_at_their_place(server, tmp_path: Path):
    path = tmp_path / "robot.lnc"
    path.write_text(ROBOT)
    assert await open_doc(server, path) == []
    broken = ROBOT.replace("depends_on: arm", "depends_on: armm")  # not saved
    [d] = await change_doc(server, path, broken, 2)
    assert d.message == "unknown process or state 'armm' in 'depends_on' of 'viewer' " \
                        "(did you mean 'arm'?)" or "armm" in d.message
    assert (d.range.start.line, d.range.start.character) == (13, 12)
    assert d.severity == lsp.DiagnosticSeverity.Error and d.source == "ln_manager check"
    assert await change_doc(server, path, ROBOT, 3) == []


async def test_broken_mid_edit_unclosed_call_and_bad_quote(server, tmp_path: Path):
    path = tmp_path / "robot.lnc"
    text = ROBOT.replace("command: viewer --base %(base)", 'command: viewer --base %(base')
    found = await open_doc(server, path, text)
    assert [(d.range.start.line, d.range.start.character, d.message) for d in found] == [
        (14, 23, "unterminated '%(' (missing ')')")]
    text = ROBOT.replace("command: viewer --base %(base)", 'command: "viewer')
    found = await change_doc(server, path, text, 2)
    assert [(d.range.start.line, d.range.start.character, d.message) for d in found][0] == \
        (14, 9, "unterminated double quote")
    # the server is still there and answers
    assert await server.text_document_document_symbol_async(
        lsp.DocumentSymbolParams(lsp.TextDocumentIdentifier(path.as_uri())))


async def test_self_include_is_a_diagnostic(server, tmp_path: Path):
    path = tmp_path / "self.lnc"
    path.write_text(ROBOT + "include self.lnc\n")
    found = await open_doc(server, path)
    assert [(d.range.start.line, d.message) for d in found] == [
        (17, "include cycle: self.lnc -> self.lnc")]


async def test_hanging_pipe_include_is_cut_off(start_server, tmp_path: Path):
    server = await start_server({"shellTimeout": 0.5})
    path = tmp_path / "hang.lnc"
    found = await open_doc(server, path, ROBOT + 'pipe_include "sleep 60"\n')
    assert [(d.range.start.line, d.message) for d in found] == [
        (17, "command 'sleep 60' did not finish within 0.5 s (killed)")]
    hover = await server.text_document_hover_async(lsp.HoverParams(**pos(path, 10, 9)))
    assert hover is not None


async def test_strict_and_defines_settings(start_server, tmp_path: Path):
    text = ROBOT + "add_message_definition_dir: no_such_dir\n"
    path = tmp_path / "robot.lnc"
    lenient = await start_server()
    [w] = await open_doc(lenient, path, text)
    assert w.severity == lsp.DiagnosticSeverity.Warning
    assert w.message == "message definition directory 'no_such_dir' not found (ignored)"
    strict = await start_server({"strict": True, "defines": ["base=/srv"]})
    [e] = await open_doc(strict, path, text)
    assert e.severity == lsp.DiagnosticSeverity.Error
    assert e.message.endswith("[warning, an error with --strict]")
    hover = await strict.text_document_hover_async(lsp.HoverParams(**pos(path, 14, 26)))
    assert "/srv" in hover.contents.value and "-D" in hover.contents.value


async def test_an_include_reads_the_open_unsaved_buffer(server, tmp_path: Path):
    inc = tmp_path / "viewer.inc.lnc"
    inc.write_text("process viewer2\ncommand: v2\n")
    main = tmp_path / "main.lnc"
    await open_doc(server, main, ROBOT + "include viewer.inc.lnc\n")
    await open_doc(server, inc, wait=False)
    # the include file's unsaved text names an unknown process: shown in the include
    found = await change_doc(server, inc, "process viewer2\ncommand: v2\ndepends_on: nope\n", 2)
    assert [(d.range.start.line, d.range.start.character) for d in found] == [(2, 12)]
    assert "'nope'" in found[0].message


async def test_hover(server, tmp_path: Path):
    path = tmp_path / "robot.lnc"
    await open_doc(server, path, ROBOT)

    async def hover(line: int, character: int) -> str:
        h = await server.text_document_hover_async(lsp.HoverParams(**pos(path, line, character)))
        return h.contents.value if h else ""

    assert "/opt/robot/bin/arm left" in await hover(13, 13)  # arm's resolved command
    assert "/opt/robot" in await hover(14, 27)  # %(base)
    assert "arm_tpl(side)" in await hover(11, 16)
    text = await hover(13, 3)
    assert text.startswith("**depends_on** (process key): implemented")
    assert "must be ready" in text  # the row of docs/configuration.md
    assert "10.0.0.2" in await hover(8, 8)  # the host


async def test_definition_and_references(server, tmp_path: Path):
    inc = tmp_path / "more.inc.lnc"
    inc.write_text("process late\ncommand: late\n")
    path = tmp_path / "robot.lnc"
    await open_doc(server, path, ROBOT + "include more.inc.lnc\n")

    async def definition(line: int, character: int) -> list:
        found = await server.text_document_definition_async(
            lsp.DefinitionParams(**pos(path, line, character)))
        return [where(x) for x in found]

    assert await definition(13, 13) == [("robot.lnc", 10, 8, 11)]  # depends_on: arm
    assert await definition(11, 16) == [("robot.lnc", 7, 9, 16)]  # the template
    assert await definition(14, 26) == [("robot.lnc", 4, 0, 4)]  # %(base)
    assert await definition(17, 10) == [("more.inc.lnc", 0, 0, 0)]  # the include
    assert await definition(8, 7) == [("robot.lnc", 6, 0, 5)]  # node: robot
    refs = await server.text_document_references_async(lsp.ReferenceParams(
        context=lsp.ReferenceContext(include_declaration=True), **pos(path, 10, 9)))
    assert sorted(where(r) for r in refs) == [("robot.lnc", 10, 8, 11),
                                              ("robot.lnc", 13, 12, 15),
                                              ("robot.lnc", 16, 9, 12)]
    refs = await server.text_document_references_async(lsp.ReferenceParams(
        context=lsp.ReferenceContext(include_declaration=False), **pos(path, 4, 1)))
    assert sorted(where(r) for r in refs) == [("robot.lnc", 9, 11, 15),
                                              ("robot.lnc", 14, 25, 29)]


async def test_completion(server, tmp_path: Path):
    path = tmp_path / "robot.lnc"
    text = ROBOT + "process third\ndepends_on: \nnode: \ncommand: %(\nfl\n"
    await open_doc(server, path, text)

    async def labels(line: int, character: int) -> set[str]:
        found = await server.text_document_completion_async(
            lsp.CompletionParams(**pos(path, line, character)))
        return {i.label for i in found.items}

    assert {"arm", "viewer", "all"} <= await labels(18, 12)
    assert "robot" in await labels(19, 6)
    assert {"base", "CURDIR", "env"} <= await labels(20, 11)
    keys = await labels(21, 2)
    assert {"flags", "command", "use_template", "process", "include"} <= keys
    assert "members" not in keys  # a group key, not a process key
    assert "members" in await labels(16, 0)


async def test_outline(server, tmp_path: Path):
    path = tmp_path / "robot.lnc"
    await open_doc(server, path, ROBOT)
    found = await server.text_document_document_symbol_async(
        lsp.DocumentSymbolParams(lsp.TextDocumentIdentifier(path.as_uri())))
    assert [(s.name, s.range.start.line, s.range.end.line) for s in found] == [
        ("instance", 0, 2), ("defines", 3, 4), ("hosts", 5, 6),
        ("template arm_tpl(side)", 7, 9), ("process arm", 10, 11),
        ("process viewer", 12, 14), ("group all", 15, 17)]
    assert [c.name for c in found[2].children] == ["robot"]
    assert [c.name for c in found[1].children] == ["base"]
