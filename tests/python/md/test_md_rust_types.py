"""`ln_generate --lang rust`: the output of every built-in md and of the real-world corpus
(../shared/real_ln/md, read in place) type-checks with rustc against the links_and_nodes
crate, its compile-time size assertions are C's sizes and really are checked, Rust keywords
become raw identifiers, and a bad md gives the same `file:line:col` error as other languages."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

import pytest
from cargo_build import rustc_check
from test_md_errors import CASES, expected_lines, write_mds

from ln_generate.cli import main

REPO = Path(__file__).resolve().parents[3]
BUILTIN = REPO / "message_definitions"


def generate(out: Path, *args: str) -> tuple[int, str]:
    """Run the CLI in process; (exit status, stderr)."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        rc = main(["-o", str(out), *args])
    return rc, err.getvalue()


def builtin_names() -> list[str]:
    """Every built-in md (not the SConscript beside them)."""
    return sorted(p.relative_to(BUILTIN).as_posix() for p in BUILTIN.rglob("*")
                  if p.is_file() and p.parent != BUILTIN)


def test_builtin_mds_compile_with_c_sizes(tmp_path: Path) -> None:
    rs, h = tmp_path / "all.rs", tmp_path / "all.h"
    assert generate(rs, *builtin_names()) == (0, "")
    assert generate(h, *builtin_names()) == (0, "")
    text = rs.read_text()
    c_sizes = dict(re.findall(r"#define (\w+_SIZE) (\d+)\n", h.read_text()))
    # every struct states its C size macro and asserts that size_of is it
    rust_sizes = re.findall(r"/// Bytes of the C layout \(`(\w+)`\)\.\n\s*pub const SIZE: "
                            r"usize = (\d+);", text)
    assert {m for m, _ in rust_sizes} == set(c_sizes)
    for macro, size in rust_sizes:
        assert size == c_sizes[macro], macro
    asserted = re.findall(r"size_of::<(\w+)>\(\) == (\d+),", text)
    assert sorted(s for t, s in asserted if t != "usize") == sorted(s for _, s in rust_sizes)
    done = rustc_check(rs)
    assert done.returncode == 0, done.stderr


def test_size_assertions_are_checked(tmp_path: Path) -> None:
    rs = tmp_path / "m.rs"
    assert generate(rs, "robot/tool_state") == (0, "")
    text = rs.read_text()
    assert "size_of::<ToolState>() == 401," in text
    rs.write_text(text.replace("size_of::<ToolState>() == 401,", "size_of::<ToolState>() == 400,"))
    done = rustc_check(rs)
    assert done.returncode != 0 and "robot/tool_state: size" in done.stderr, done.stderr


def test_real_world_mds_compile(tmp_path: Path) -> None:
    """One crate, one module per md (some sets hold an md under two names, which generate
    the same Rust type, so each md gets its own output and module)."""
    # imported here: without the corpus it fails in CI and skips elsewhere, for this test only
    from test_md_real_world import CORPUS_SIZE, EXPECTED_FAILURES, md_names, md_sets

    modules = []
    for md_set in md_sets():
        for name in md_names(md_set):
            out = tmp_path / f"md{len(modules)}.rs"
            rc, err = generate(out, "--lang", "rust", "--md-dir", str(md_set), name)
            key = f"{md_set.name}/{name}"
            if key in EXPECTED_FAILURES:
                assert (rc, err) == (1, f"{md_set / name}:{EXPECTED_FAILURES[key][1]}\n")
                continue
            assert rc == 0, (key, err)
            modules.append(f'mod {out.stem} {{ include!("{out}"); }}')
    assert len(modules) == CORPUS_SIZE - len(EXPECTED_FAILURES)
    crate = tmp_path / "corpus.rs"
    crate.write_text("\n".join(modules) + "\n")
    done = rustc_check(crate)
    assert done.returncode == 0, done.stderr[:5000]


def test_rust_keywords_are_raw_identifiers(tmp_path: Path) -> None:
    md = tmp_path / "md"
    write_mds(md, {"match/type": b"double type\nint32_t fn\nuint8_t loop[2]\n",
                   "match/ask": b'define t as "match/type"\nservice\nrequest\nt* impl\nchar* '
                                b'ref\nresponse\nt where\n'})
    rs = tmp_path / "kw.rs"
    assert generate(rs, "--md-dir", str(md), "match/type", "match/ask") == (0, "")
    text = rs.read_text()
    for item in ("pub mod r#match {", "pub r#type: f64,", "pub r#fn: i32,", "pub r#loop: [u8; 2],",
                 "pub r#impl: ::std::vec::Vec<Type>,", "pub r#ref: ::std::string::String,",
                 "pub r#where: Type,"):
        assert item in text, item
    done = rustc_check(rs)
    assert done.returncode == 0, done.stderr


def test_names_that_cannot_be_rust_are_refused(tmp_path: Path) -> None:
    md = tmp_path / "md"
    write_mds(md, {"t/m": b"double x\nint32_t self\n", "super/m": b"double x\n"})
    out = tmp_path / "x.rs"
    assert generate(out, "--md-dir", str(md), "t/m") == (
        1, f"{md / 't/m'}:2:9: field name 'self' cannot be a Rust identifier\n")
    assert generate(out, "--md-dir", str(md), "super/m") == (
        1, f"{md / 'super/m'}:1:1: md name 'super/m': component 'super' cannot be a Rust "
           "module name\n")
    assert not out.exists()


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_bad_md_same_error_as_other_languages(case, tmp_path: Path) -> None:  # noqa: ANN001
    _, files, name, lines = case
    md_dir = tmp_path / "md"
    write_mds(md_dir, files)
    out = tmp_path / "out" / "gen.rs"
    rc, err = generate(out, "--md-dir", str(md_dir), name)
    assert (rc, err.splitlines()) == (1, expected_lines(md_dir, lines))
    assert not out.exists()
