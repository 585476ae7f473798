"""ln_lsp on message definitions beyond syntax: imports and field types resolved as
ln_generate resolves them when generating (beside the md, the mdDirs setting, the built-in
message_definitions/), each problem at the place of the name it is about."""

from __future__ import annotations

from pathlib import Path

from lsprotocol import types as lsp

from .helpers import change_doc, open_doc

TEXT = """define t as "ln/time"
define s as "robot/plan_path"
define b as "broken"
define q as "robot/nowhere"
t stamp
dobule x
q y
b z
s w
"""


def at(d: lsp.Diagnostic) -> tuple[int, int, int]:
    r = d.range
    assert r.start.line == r.end.line
    return r.start.line, r.start.character, r.end.character


async def test_unknown_types_and_imports_that_do_not_resolve(start_server, tmp_path: Path):
    msgs = tmp_path / "msgs"
    (msgs / "robot").mkdir(parents=True)
    broken = msgs / "robot" / "broken"  # found beside the md as "robot/broken"
    broken.write_text("uint8_t ok\nflaot f\n")
    path = msgs / "robot" / "checked"
    server = await start_server({"mdDirs": [str(msgs)]})
    found = await open_doc(server, path, TEXT, language="lnmd")
    assert [at(d) for d in found] == [(1, 13, 28), (2, 13, 19), (3, 13, 26), (5, 0, 6)]
    assert all(d.severity == lsp.DiagnosticSeverity.Error for d in found)
    assert found[0].message == ("'robot/plan_path' is a service, not a message; "
                                "only messages can be used as field types")
    assert found[1].message == (f"in 'broken': {broken}:2:1: unknown type 'flaot' "
                                "(did you mean 'float'?)")
    assert found[2].message.startswith("message definition 'robot/nowhere' not found "
                                       f"(searched: {msgs / 'robot'}, {msgs}, ")
    assert found[3].message == "unknown type 'dobule' (did you mean 'double'?)"
    # fixed: 'ln/time' resolves through the built-in message_definitions/
    broken.write_text("uint8_t ok\nfloat f\n")
    fixed = "define t as \"ln/time\"\ndefine b as \"broken\"\nt stamp\ndouble x\nb z\n"
    assert await change_doc(server, path, fixed, 2) == []


async def test_a_local_type_name_is_not_unknown_and_syntax_comes_first(start_server,
                                                                       tmp_path: Path):
    server = await start_server({"mdDirs": [str(tmp_path)]})
    path = tmp_path / "robot" / "pair"
    path.parent.mkdir()
    text = 'define p as "robot/pose"\np a\npose b\ndouble c[2*]\n'
    found = await open_doc(server, path, text, language="lnmd")
    assert [(at(d), d.message) for d in found] == [
        ((3, 11, 12), "incomplete array size expression"),
        ((2, 0, 4), "unknown type 'pose'")]
