"""ln_lsp on included files that are not open: their problems are summarised on the include
line (the include's argument) of the open file that leads to them, directly or through
other files that are not open; once open, a file shows its own diagnostics."""

from __future__ import annotations

from pathlib import Path

from lsprotocol import types as lsp

from .helpers import diagnostics_for, open_doc

MAIN = "instance\nname: t\nmanager: :54999\ninclude {}\n"
WARN = "message definition directory 'no_such_dir' not found (ignored)"


def at(d: lsp.Diagnostic) -> tuple[int, int, int, int]:
    r = d.range
    return r.start.line, r.start.character, r.end.line, r.end.character


async def test_an_included_file_that_is_not_open(server, tmp_path: Path):
    sub = tmp_path / "sub.inc.lnc"
    sub.write_text("add_message_definition_dir: no_such_dir\n"
                   "process helper\ncommand: helper\ndepends_on: nope\n")
    main = tmp_path / "main.lnc"
    [d] = await open_doc(server, main, MAIN.format("sub.inc.lnc"))
    assert at(d) == (3, 8, 3, 19)  # the argument of the include
    assert d.severity == lsp.DiagnosticSeverity.Error  # the worst: an error and a warning
    assert d.message == ("included file 'sub.inc.lnc' has 2 problems; the first: "
                         f"sub.inc.lnc:1:29: {WARN}")
    # opened, the file shows its own problems, and the summary goes away
    start = len(server.published)
    own = await open_doc(server, sub)
    assert [(at(x), x.severity) for x in own] == [
        ((3, 12, 3, 16), lsp.DiagnosticSeverity.Error),
        ((0, 28, 0, 39), lsp.DiagnosticSeverity.Warning)]
    assert own[1].message == WARN and "'nope'" in own[0].message
    assert await diagnostics_for(server, main.as_uri(), 1, start) == []


async def test_a_nested_include_is_shown_on_the_open_file_that_leads_to_it(
        server, tmp_path: Path):
    inc = tmp_path / "inc"
    inc.mkdir()
    (inc / "b.inc.lnc").write_text("process b\ncommand: b\ninclude c.inc.lnc\n")
    (inc / "c.inc.lnc").write_text("# c\nadd_message_definition_dir: no_such_dir\n")
    main = tmp_path / "a.lnc"
    [d] = await open_doc(server, main, MAIN.format("inc/b.inc.lnc"))
    assert at(d) == (3, 8, 3, 21)  # a's line that leads to c (through b, not open)
    assert d.severity == lsp.DiagnosticSeverity.Warning
    assert d.message == ("included file 'inc/c.inc.lnc' has 1 problem; the first: "
                         f"inc/c.inc.lnc:2:29: {WARN}")
    # b opened: the summary of c moves to b's include line, a has nothing left
    start = len(server.published)
    [on_b] = await open_doc(server, inc / "b.inc.lnc")
    assert at(on_b) == (2, 8, 2, 17)
    assert on_b.message.startswith("included file 'inc/c.inc.lnc' has 1 problem;")
    assert await diagnostics_for(server, main.as_uri(), 1, start) == []
