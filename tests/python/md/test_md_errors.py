"""Every kind of broken message definition: exact `file:line:col: message`, exit 1, no output.

Each case writes its md files into a fresh md dir and runs the generator's CLI in
process; one case also runs it as a subprocess to check the real exit status.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from ln_generate.cli import main

REPO = Path(__file__).resolve().parents[3]

# (case id, {md name: file bytes}, md name to generate, expected stderr lines with
# paths relative to the md dir)
CASES: list[tuple[str, dict[str, bytes], str, list[str]]] = [
    ("unknown_type", {"t/m": b"double a\ndoubel x\n"}, "t/m",
     ["t/m:2:1: unknown type 'doubel' (did you mean 'double'?)"]),
    ("unknown_type_no_hint", {"t/m": b"quaternion q\n"}, "t/m",
     ["t/m:1:1: unknown type 'quaternion'"]),
    ("unknown_type_hint_alias", {"t/m": b'define pose as "t/p"\npoze p\n', "t/p": b"double x\n"},
     "t/m", ["t/m:2:1: unknown type 'poze' (did you mean 'pose'?)"]),
    ("duplicate_field", {"t/m": b"double x\nint  x\n"}, "t/m",
     ["t/m:2:6: duplicate field 'x' (first defined at line 1)"]),
    ("duplicate_implicit_len", {"t/m": b"char* name\nuint32_t name_len\n"}, "t/m",
     ["t/m:2:10: field 'name_len' clashes with the implicit length field of 'name' "
      "(first defined at line 1)"]),
    ("implicit_len_clash", {"t/m": b"uint32_t name_len\nchar* name\n"}, "t/m",
     ["t/m:2:7: implicit length field 'name_len' of 'name' clashes with field 'name_len' "
      "(first defined at line 1)"]),
    ("array_size_zero", {"t/m": b"double m[0]\n"}, "t/m",
     ["t/m:1:10: array size must be positive, got 0"]),
    ("array_size_negative", {"t/m": b"double m[2-5]\n"}, "t/m",
     ["t/m:1:10: array size must be positive, got -3"]),
    ("array_size_incomplete", {"t/m": b"double m[3*]\n"}, "t/m",
     ["t/m:1:12: incomplete array size expression"]),
    ("array_size_not_integer", {"t/m": b"double m[n]\n"}, "t/m",
     ["t/m:1:10: array size must be an integer expression, not 'n'"]),
    ("array_size_fraction", {"t/m": b"double m[7/2]\n"}, "t/m",
     ["t/m:1:11: array size 7/2 is not a whole number"]),
    ("array_size_missing", {"t/m": b"double m[]\n"}, "t/m", ["t/m:1:10: missing array size"]),
    ("array_dynamic_and_static", {"t/m": b"double* m[3]\n"}, "t/m",
     ["t/m:1:10: dynamic field 'm' cannot also have a static size"]),
    ("unknown_import", {"t/m": b'define p as "t/nothere"\np pose\n'}, "t/m",
     ["t/m:1:14: message definition 't/nothere' not found (searched: {root}/t, {dirs})"]),
    ("import_cycle", {"t/a": b'define b as "t/b"\nb x\n', "t/b": b'define c as "t/c"\nc y\n',
                      "t/c": b'define a as "t/a"\na z\n'}, "t/a",
     ["t/c:1:14: import cycle: t/a -> t/b -> t/c -> t/a"]),
    ("self_import", {"t/a": b'define me as "t/a"\nme x\n'}, "t/a",
     ["t/a:1:15: import cycle: t/a -> t/a"]),
    ("escape_dotdot", {"t/m": b'define p as "../etc/passwd"\np x\n'}, "t/m",
     ["t/m:1:14: message definition name '../etc/passwd' escapes its directory"]),
    ("escape_inner_dotdot", {"t/m": b'define p as "t/../../x"\np x\n'}, "t/m",
     ["t/m:1:14: message definition name 't/../../x' escapes its directory"]),
    ("escape_absolute", {"t/m": b'define p as "/etc/passwd"\np x\n'}, "t/m",
     ["t/m:1:14: message definition name '/etc/passwd' must be relative, not absolute"]),
    ("import_of_service", {"t/m": b'define s as "t/s"\ns x\n',
                           "t/s": b"service\nrequest\nint a\nresponse\nint b\n"}, "t/m",
     ["t/m:1:14: 't/s' is a service, not a message; only messages can be used as field types"]),
    ("service_without_sections", {"t/s": b"service\n"}, "t/s",
     ["t/s:1:1: service has no 'request' section", "t/s:1:1: service has no 'response' section"]),
    ("event_without_call", {"t/e": b"event\nconnect\nint a\n"}, "t/e",
     ["t/e:1:1: event has no 'call' section"]),
    ("unknown_section", {"t/s": b"service\nrequest\ndouble a\nreply\nint b\n"}, "t/s",
     ["t/s:4:1: unknown section keyword 'reply' (expected 'request' or 'response')"]),
    ("event_section_in_service", {"t/s": b"service\nrequest\ncall\nresponse\n"}, "t/s",
     ["t/s:3:1: unknown section keyword 'call' (expected 'request' or 'response')"]),
    ("section_outside_service", {"t/m": b"request\ndouble x\n"}, "t/m",
     ["t/m:1:1: section keyword 'request' outside a service (start the file with 'service')"]),
    ("field_before_section", {"t/s": b"service\ndouble a\nrequest\nresponse\n"}, "t/s",
     ["t/s:2:1: field outside a section (a service starts with 'request')"]),
    ("late_service_keyword", {"t/s": b"double a\nservice\n"}, "t/s",
     ["t/s:2:1: 'service' must come before any section or field"]),
    ("trailing_garbage", {"t/m": b"double x extra\n"}, "t/m",
     ["t/m:1:10: unexpected 'extra' after field 'x'"]),
    ("trailing_after_array", {"t/m": b"double x[3] 4\n"}, "t/m",
     ["t/m:1:13: unexpected '4' after field 'x'"]),
    ("trailing_after_define", {"t/m": b'define p as "t/p" junk\np x\n', "t/p": b"int a\n"}, "t/m",
     ["t/m:1:19: unexpected 'junk' after define"]),
    ("bad_define", {"t/m": b"define p t/p\n"}, "t/m",
     ['t/m:1:10: expected: define LOCAL_TYPE as "md/name"']),
    ("non_utf8", {"t/m": b"double ok\ndouble x\xff\n"}, "t/m",
     ["t/m:2:9: file is not valid UTF-8 (invalid byte 0xff)"]),
    ("empty_file", {"t/m": b""}, "t/m", ["t/m:1:1: empty message definition (no fields)"]),
    ("only_comments", {"t/m": b"# nothing here\n\n   # still nothing\n"}, "t/m",
     ["t/m:1:1: empty message definition (no fields)"]),
    ("only_defines", {"t/m": b'define p as "t/p"\n', "t/p": b"int a\n"}, "t/m",
     ["t/m:1:1: empty message definition (only defines, no fields)"]),
    ("reserved_word", {"t/m": b"double class\n"}, "t/m",
     ["t/m:1:8: field name 'class' is a reserved word in C++"]),
    ("reserved_python", {"t/m": b"int lambda\n"}, "t/m",
     ["t/m:1:5: field name 'lambda' is a reserved word in Python"]),
    ("bad_character", {"t/m": b"double x;\n"}, "t/m", ["t/m:1:9: unexpected character ';'"]),
    ("bad_number", {"t/m": b"double x[3a]\n"}, "t/m", ["t/m:1:10: bad number '3a'"]),
    ("unterminated_string", {"t/m": b'define p as "t/p\n'}, "t/m", ["t/m:1:13: unterminated string"]),
    ("several_errors_at_once", {"t/m": b"doubel a\ndouble b[0]\nint c junk\n"}, "t/m",
     ["t/m:1:1: unknown type 'doubel' (did you mean 'double'?)",
      "t/m:2:10: array size must be positive, got 0",
      "t/m:3:7: unexpected 'junk' after field 'c'"]),
]


def write_mds(root: Path, files: dict[str, bytes]) -> None:
    for name, data in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)


def expected_lines(root: Path, lines: list[str]) -> list[str]:
    from ln_generate.lookup import default_md_dirs

    dirs = ", ".join(str(d) for d in default_md_dirs([str(root)]))
    return [f"{root}/{line.format(dirs=dirs, root=root)}" for line in lines]


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_error_case(case, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _, files, name, lines = case
    md_dir = tmp_path / "md"
    write_mds(md_dir, files)
    out = tmp_path / "out" / "gen.h"
    assert main(["-o", str(out), "--md-dir", str(md_dir), name]) == 1
    captured = capsys.readouterr()
    assert captured.err.splitlines() == expected_lines(md_dir, lines)
    assert captured.out == ""
    assert not out.exists()
    assert not out.parent.exists() or not any(out.parent.iterdir())


def test_symlink_escaping_its_directory(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    outside = tmp_path / "outside"
    outside.write_text("double secret\n")
    md_dir = tmp_path / "md"
    write_mds(md_dir, {"t/m": b'define p as "t/link"\np x\n'})
    (md_dir / "t" / "link").symlink_to(outside)
    assert main(["-o", str(tmp_path / "gen.h"), "--md-dir", str(md_dir), "t/m"]) == 1
    assert capsys.readouterr().err.splitlines() == [
        f"{md_dir}/t/m:1:14: message definition 't/link' in '{md_dir}' resolves to "
        f"'{outside}', outside its directory"
    ]


def test_symlink_inside_its_directory_is_fine(tmp_path: Path) -> None:
    md_dir = tmp_path / "md"
    write_mds(md_dir, {"t/real": b"double x\n", "t/m": b'define p as "t/alias"\np a\n'})
    (md_dir / "t" / "alias").symlink_to(md_dir / "t" / "real")
    assert main(["-o", str(tmp_path / "gen.h"), "--md-dir", str(md_dir), "t/m"]) == 0


def test_bad_name_on_command_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["-o", str(tmp_path / "gen.h"), "--md-dir", str(tmp_path), "../x"]) == 1
    assert capsys.readouterr().err.splitlines() == [
        "<command line>:1:1: message definition name '../x' escapes its directory"
    ]


def test_error_leaves_existing_output_untouched(tmp_path: Path) -> None:
    md_dir = tmp_path / "md"
    write_mds(md_dir, {"t/m": b"double x\n"})
    out = tmp_path / "gen.h"
    assert main(["-o", str(out), "--md-dir", str(md_dir), "t/m"]) == 0
    before = out.read_bytes()
    (md_dir / "t" / "m").write_bytes(b"doubel x\n")
    assert main(["-o", str(out), "--md-dir", str(md_dir), "t/m"]) == 1
    assert out.read_bytes() == before


def test_exit_status_of_the_real_command(tmp_path: Path) -> None:
    md_dir = tmp_path / "md"
    write_mds(md_dir, {"t/m": b"double x[0]\n"})
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    cmd = [sys.executable, "-m", "ln_generate", "-o", str(tmp_path / "g.h"), "--md-dir", str(md_dir)]
    bad = subprocess.run([*cmd, "t/m"], capture_output=True, text=True, env=env, check=False)
    assert bad.returncode == 1
    assert bad.stderr == f"{md_dir}/t/m:1:10: array size must be positive, got 0\n"
    usage = subprocess.run(cmd[:3] + ["-o", "x.unknown", "t/m"], capture_output=True, text=True,
                           env=env, check=False)
    assert usage.returncode == 2
    assert "cannot tell the language" in usage.stderr
