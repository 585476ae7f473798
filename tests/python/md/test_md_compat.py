"""The rules that make mds written for the original Links and Nodes work: a service with
only one section, `define` looked up next to the md first, repeated sections merged with
a warning; and the explicit `NAME_len` beside `T* NAME` that stays an error.
"""

from __future__ import annotations

import ctypes
import subprocess
from pathlib import Path

import pytest
from gen_modules import load_module

from ln_generate import MdError, MdRegistry
from ln_generate.cli import main

RESPONSE_ONLY = b"service\nresponse\nuint64_t maxever\n"
REQUEST_ONLY = b"service\nrequest\nchar* name\n"


def write_mds(root: Path, files: dict[str, bytes]) -> Path:
    for name, data in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
    return root


def generate(root: Path, name: str, out: Path, capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    rc = main(["--md-dir", str(root), "-o", str(out), name])
    captured = capsys.readouterr()
    assert captured.out == ""
    return rc, captured.err


def compile_header(path: Path) -> None:
    cmd = (["gcc", "-std=c11", "-x", "c"] if path.suffix == ".h"
           else ["g++", "-std=c++17", "-x", "c++"])
    cc = subprocess.run([*cmd, "-Wall", "-Wextra", "-Werror", "-pedantic", "-fsyntax-only",
                         str(path)], capture_output=True, text=True)
    assert cc.returncode == 0, cc.stderr


# -- a service with only one section ------------------------------------------------------


def test_response_only_service_has_an_empty_request(tmp_path: Path) -> None:
    md = MdRegistry([write_mds(tmp_path, {"t/r": RESPONSE_ONLY})]).load("t/r")
    assert list(md.sections) == ["request", "response"]
    assert (md.sections["request"].fields, md.sections["request"].size) == ([], 0)
    assert md.sections["response"].size == 8
    assert md.signature == "|uint64_t 8 1"


def test_request_only_service_has_an_empty_response(tmp_path: Path) -> None:
    md = MdRegistry([write_mds(tmp_path, {"t/q": REQUEST_ONLY})]).load("t/q")
    assert list(md.sections) == ["request", "response"]
    assert (md.sections["response"].fields, md.sections["response"].size) == ([], 0)
    assert md.signature == "uint32_t 4 1,char* 1 1|"


def test_missing_section_is_the_same_as_an_empty_one(tmp_path: Path) -> None:
    reg = MdRegistry([write_mds(tmp_path, {
        "t/short": RESPONSE_ONLY, "t/full": b"service\nrequest\nresponse\nuint64_t maxever\n",
        "t/swapped": b"service\nresponse\nuint64_t maxever\nrequest\n"})])
    short, full, swapped = (reg.load(n) for n in ("t/short", "t/full", "t/swapped"))
    assert short.layout_hash == full.layout_hash == swapped.layout_hash
    assert short.signature == full.signature == swapped.signature
    assert list(swapped.sections) == ["request", "response"]  # canonical order, not file order


def test_response_only_service_generated_layout(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    root = write_mds(tmp_path / "md", {"t/r": RESPONSE_ONLY})
    for suffix in (".h", ".hpp", ".py"):
        assert generate(root, "t/r", tmp_path / f"r{suffix}", capsys) == (0, "")
    c = (tmp_path / "r.h").read_text()
    assert ("typedef struct t_r_request {\n"
            "    uint8_t _ln_empty; /* C has no empty structs; not part of the layout */\n"
            "} t_r_request_t;\n") in c
    assert ("typedef struct t_r {\n    t_r_request_t req;\n    t_r_response_t resp;\n} t_r_t;\n"
            in c)
    assert "#define T_R_REQUEST_SIZE 0\n#define T_R_RESPONSE_SIZE 8\n" in c
    assert '#define T_R_SIGNATURE "|uint64_t 8 1"\n' in c
    cpp = (tmp_path / "r.hpp").read_text()
    assert "    struct request_t {\n        std::uint8_t _ln_empty;" in cpp
    assert "inline constexpr std::size_t r_request_size = 0;" in cpp
    compile_header(tmp_path / "r.h")
    compile_header(tmp_path / "r.hpp")

    mod = load_module("compat_response_only", tmp_path / "r.py")
    req_cls, resp_cls = mod.t_r_request_t, mod.t_r_response_t
    assert (req_cls.SIZE, ctypes.sizeof(req_cls)) == (0, 1)  # placeholder byte, as in C
    assert (resp_cls.SIZE, ctypes.sizeof(resp_cls)) == (8, 8)
    assert [n for n, _ in mod.t_r_t._fields_] == ["req", "resp"]
    assert ctypes.sizeof(mod.t_r_t) == 9  # == sizeof(t_r_t) in C: 1 + 8
    assert mod.t_r_t.SIGNATURE == "|uint64_t 8 1"
    assert req_cls().to_dict() == {}
    resp = resp_cls.from_dict({"maxever": 2**40})
    assert resp.maxever == 2**40
    assert resp_cls.from_buffer_copy(bytes(resp)).to_dict() == {"maxever": 2**40}


def test_request_only_service_works_in_python(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    root = write_mds(tmp_path / "md", {"t/q": REQUEST_ONLY})
    for suffix in (".h", ".hpp", ".py"):
        assert generate(root, "t/q", tmp_path / f"q{suffix}", capsys) == (0, "")
    compile_header(tmp_path / "q.h")
    compile_header(tmp_path / "q.hpp")
    mod = load_module("compat_request_only", tmp_path / "q.py")
    req = mod.t_q_request_t.from_dict({"name": "arm"})
    assert req.to_dict() == {"name": "arm"}
    assert (mod.t_q_response_t.SIZE, ctypes.sizeof(mod.t_q_response_t)) == (0, 1)
    assert mod.t_q_response_t().to_dict() == {}


def test_service_without_any_section_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(MdError) as e:
        MdRegistry([write_mds(tmp_path, {"t/s": b"service\n# nothing\n"})]).load("t/s")
    assert str(e.value).splitlines() == [f"{tmp_path}/t/s:1:1: service has no 'request' section",
                                         f"{tmp_path}/t/s:1:1: service has no 'response' section"]


# -- define: next to the md first, then the md dirs ---------------------------------------


def test_define_next_to_the_md_wins(tmp_path: Path) -> None:
    root = write_mds(tmp_path, {
        "a/b/m": b'define string as "string"\nstring s\n',
        "a/b/string": b"char* data\n",
        "string": b"double x\n",
    })
    md = MdRegistry([root]).load("a/b/m")
    imported = md.imports["string"]
    assert (imported.name, imported.path) == ("a/b/string", root / "a/b/string")
    assert md.signature == "[uint32_t 4 1,char* 1 1] 12 1"


def test_define_falls_back_to_the_md_dirs(tmp_path: Path) -> None:
    root = write_mds(tmp_path, {"a/b/m": b'define p as "p"\np s\n', "p": b"double x\n"})
    assert MdRegistry([root]).load("a/b/m").imports["p"].name == "p"


def test_define_with_a_folder_is_relative_too(tmp_path: Path) -> None:
    root = write_mds(tmp_path, {
        "a/m": b'define d as "kv/desc"\nd x\n',
        "a/kv/desc": b'define string as "string"\nstring unit\n',  # next to a/kv/desc
        "a/kv/string": b"char* data\n",
    })
    md = MdRegistry([root]).load("a/m")
    assert md.imports["d"].name == "a/kv/desc"
    assert md.imports["d"].imports["string"].name == "a/kv/string"


def test_define_next_to_the_md_beats_an_earlier_md_dir(tmp_path: Path) -> None:
    first = write_mds(tmp_path / "first", {"svc/string": b"double x\n"})
    second = write_mds(tmp_path / "second", {
        "svc/list": b'service\nresponse\ndefine string as "string"\nstring* names\n',
        "svc/string": b"char* data\n",
    })
    md = MdRegistry([first, second]).load("svc/list")
    assert md.imports["string"].path == second / "svc/string"


def test_one_md_name_for_two_files_is_an_error(tmp_path: Path) -> None:
    first = write_mds(tmp_path / "first", {"a/string": b"double x\n"})
    second = write_mds(tmp_path / "second", {
        "a/m": b'define string as "string"\nstring s\n', "a/string": b"char* data\n"})
    reg = MdRegistry([first, second])
    reg.load("a/string")
    with pytest.raises(MdError) as e:
        reg.load("a/m")
    assert str(e.value) == (f"{second}/a/m:1:19: '{second}/a/string' would be the message "
                            f"definition 'a/string', which is already '{first}/a/string'")


def test_define_not_found_names_every_place_searched(tmp_path: Path) -> None:
    root = write_mds(tmp_path, {"a/b/m": b'define s as "nothere"\ns x\n'})
    with pytest.raises(MdError) as e:
        MdRegistry([root]).load("a/b/m")
    assert str(e.value) == (f"{root}/a/b/m:1:14: message definition 'nothere' not found "
                            f"(searched: {root}/a/b, {root})")


def test_define_generates_the_relative_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    root = write_mds(tmp_path / "md", {
        "kv/list": b'service\nresponse\ndefine string as "string"\nstring* names\n',
        "kv/string": b"char* data\n",
    })
    assert generate(root, "kv/list", tmp_path / "l.h", capsys) == (0, "")
    text = (tmp_path / "l.h").read_text()
    assert "} kv_string_t;" in text and "    kv_string_t* names;" in text
    compile_header(tmp_path / "l.h")


# -- repeated sections are merged, with a warning -----------------------------------------


DUPLICATE = b"service\nrequest\nint32_t a\nresponse\nuint64_t state\n\n  response\nchar* error\n"


def test_duplicate_sections_are_merged_with_a_warning(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    root = write_mds(tmp_path / "md", {"t/s": DUPLICATE})
    out = tmp_path / "s.h"
    rc, err = generate(root, "t/s", out, capsys)
    assert (rc, err) == (0, f"{root}/t/s:7:3: warning: section 'response' appears again "
                            "(first at line 4); its fields are appended to it\n")
    assert out.exists()
    reg = MdRegistry([root])
    md = reg.load("t/s")
    assert [f.name for f in md.sections["response"].fields] == ["state", "error"]
    assert [f.name for f in md.sections["request"].fields] == ["a"]
    assert [str(w) for w in reg.warnings] == [err.rstrip("\n")]


def test_fields_after_a_repeated_section_go_to_it(tmp_path: Path) -> None:
    md = MdRegistry([write_mds(tmp_path, {
        "t/s": b"service\nrequest\nint32_t a\nresponse\nint32_t r\nrequest\nint32_t b\n"})]).load("t/s")
    assert [f.name for f in md.sections["request"].fields] == ["a", "b"]
    assert [f.name for f in md.sections["response"].fields] == ["r"]
    assert md.signature == "int32_t 4 1,int32_t 4 1|int32_t 4 1"


def test_merged_sections_still_refuse_duplicate_fields(tmp_path: Path) -> None:
    with pytest.raises(MdError) as e:
        MdRegistry([write_mds(tmp_path, {
            "t/s": b"service\nrequest\nint32_t a\nrequest\ndouble a\nresponse\n"})]).load("t/s")
    assert str(e.value) == f"{tmp_path}/t/s:5:8: duplicate field 'a' (first defined at line 3)"


# -- an explicit NAME_len beside T* NAME stays an error -----------------------------------


@pytest.mark.parametrize("text, expected", [
    (b"service\nrequest\nuint64_t data_adr\nuint32_t data_len\nuint8_t* data\nresponse\n",
     "5:10: implicit length field 'data_len' of 'data' clashes with field 'data_len' "
     "(first defined at line 4)"),
    (b"uint8_t* data\nuint32_t data_len\n",
     "2:10: field 'data_len' clashes with the implicit length field of 'data' "
     "(first defined at line 1)"),
], ids=["len_first", "len_after"])
def test_explicit_len_beside_dynamic_field_is_an_error(
    text: bytes, expected: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    root = write_mds(tmp_path / "md", {"t/w": text})
    out = tmp_path / "w.h"
    assert generate(root, "t/w", out, capsys) == (1, f"{root}/t/w:{expected}\n")
    assert not out.exists()
