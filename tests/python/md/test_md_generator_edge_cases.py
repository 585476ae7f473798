"""Definitions at the edges of what the generator accepts: each either works or is refused.

For every case the generator must either reject the definition with an MdError, or
produce C, C++ and Python that compile (strict and GNU modes) and behave.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from gen_modules import load_module

import ln_generate
from ln_generate import (
    MdError,
    MdRegistry,
    MessageDef,
    default_md_dirs,
    emit_c,
    emit_cpp,
    emit_python,
)
from ln_generate.emit_c import struct_c_name
from ln_generate.names import c_name

COMPILERS = [
    ["gcc", "-std=c11", "-Wall", "-Wextra", "-Werror", "-pedantic", "-x", "c"],
    ["gcc", "-std=gnu17", "-Wall", "-Wextra", "-Werror", "-x", "c"],
    ["g++", "-std=c++17", "-Wall", "-Wextra", "-Werror", "-x", "c++"],
    ["g++", "-std=gnu++17", "-Wall", "-Wextra", "-Werror", "-x", "c++"],
]


def cpp_type(md: MessageDef, section: str) -> str:
    *ns, leaf = md.name.split("/")
    path = "::" + "::".join([*ns, f"{leaf}_t"])
    return f"{path}::{section}_t" if section else path


def generate_or_refuse(tmp: Path, files: dict[str, bytes], names: list[str],
                       expect: str) -> None:
    """Write `files` as mds; the generator must refuse `names` (expect "refuse") or produce
    working code (expect "accept")."""
    root = tmp / "md"
    for name, data in files.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_bytes(data)
    registry = MdRegistry(default_md_dirs([str(root)]))
    version = ln_generate.__version__
    if expect == "refuse":
        with pytest.raises(MdError):
            mds = [registry.load(n) for n in names]
            for e, sfx in [(emit_c, ".h"), (emit_cpp, ".hpp"), (emit_python, ".py")]:
                e.emit(mds, tmp / f"out{sfx}", version)
        return
    assert expect == "accept"
    mds = [registry.load(n) for n in names]
    texts = {sfx: e.emit(mds, tmp / f"out{sfx}", version)
             for e, sfx in [(emit_c, ".h"), (emit_cpp, ".hpp"), (emit_python, ".py")]}
    for sfx, text in texts.items():
        (tmp / f"out{sfx}").write_text(text)
    # Use every type under the name the naming rules promise, in C and in C++.
    uses_c = ['#include "out.h"']
    uses_cpp = ['#include "out.hpp"']
    for md in mds:
        for i, (sec, s) in enumerate(md.sections.items()):
            uses_c.append(f"unsigned long c_{c_name(md.name)}_{i} = sizeof({struct_c_name(s)});")
            uses_cpp.append(
                f"static_assert(sizeof({cpp_type(md, sec)}) == {s.size or 1}, \"{md.name}\");"
            )
    (tmp / "use.c").write_text("\n".join(uses_c) + "\n")
    (tmp / "use.cpp").write_text("\n".join(uses_cpp) + "\n")
    for cmd in COMPILERS:
        src = tmp / ("use.c" if cmd[0] == "gcc" else "use.cpp")
        result = subprocess.run([*cmd, "-fsyntax-only", str(src)], capture_output=True, text=True)
        assert result.returncode == 0, f"{' '.join(cmd)}:\n{result.stderr}"
    module = load_module(f"lntest_edge_{tmp.name}", tmp / "out.py")
    for md in mds:
        cls = module.MESSAGES[md.name]
        assert cls.MD_NAME == md.name
        for s in md.sections.values():
            assert getattr(module, struct_c_name(s)).MD_NAME == md.name, struct_c_name(s)
        obj = cls.from_buffer_copy(bytes(cls()))
        assert cls.from_dict(obj.to_dict()).to_dict() == obj.to_dict()
        assert obj.copy().to_dict() == obj.to_dict()


COMMENT_CASES = [
    pytest.param("doc", "ends in a \"quote\""),
    pytest.param("field", "ends in a \"quote\""),
    pytest.param("doc", "see /* nested"),
    pytest.param("field", "see /* nested"),
    pytest.param("doc", "ends in a backslash \\"),
    pytest.param("field", "ends in a backslash \\"),
    pytest.param("doc", "closes */ early"),
    pytest.param("field", "closes */ early"),
    pytest.param("field", "a NUL \0 byte"),
    pytest.param("field", "triple ''' and \"\"\" quotes"),
]


@pytest.mark.parametrize(("where", "text"), COMMENT_CASES)
def test_comment_text(tmp_path: Path, where: str, text: str) -> None:
    body = f"# {text}\ndouble a\n" if where == "doc" else f"double a # {text}\nuint8_t b\n"
    generate_or_refuse(tmp_path, {"edge/m": body.encode()}, ["edge/m"], "accept")


NAME_CASES = [
    ("update", "refuse"),
    ("from_buffer_copy", "refuse"),
    ("_Pragma", "refuse"),
    ("_Float32", "refuse"),
    ("NULL", "refuse"),
    ("INT8_MAX", "refuse"),
    ("linux", "refuse"),
    ("offsetof", "refuse"),
    ("uint32_t", "accept"),
    ("std", "accept"),
]


@pytest.mark.parametrize(("name", "expect"), NAME_CASES)
def test_field_name(tmp_path: Path, name: str, expect: str) -> None:
    body = f"double {name}\nuint32_t after\n"
    generate_or_refuse(tmp_path, {"edge/m": body.encode()}, ["edge/m"], expect)


MD_NAME_CASES = [
    pytest.param(
        {"p/svc": b"service\nrequest\ndouble a\nresponse\ndouble b\n",
         "p/svc_request": b"double q\n"},
        id="section-vs-message",
    ),
    pytest.param(
        {"p/pose": b"double x[3]\n", "P/pose": b"double x[3]\n"},
        id="case-only",
    ),
    pytest.param({"int8": b"double a\n"}, id="int8"),
    pytest.param({"class/thing": b"double a\n"}, id="cpp-keyword-namespace"),
    pytest.param({"a_b/c": b"double a\n", "a/b_c": b"double a\n"}, id="underscore-clash"),
]


@pytest.mark.parametrize("files", MD_NAME_CASES)
def test_md_names(tmp_path: Path, files: dict[str, bytes]) -> None:
    generate_or_refuse(tmp_path, files, list(files), "refuse")  # every case here clashes


def test_char_scalar_dict_round_trip(tmp_path: Path) -> None:
    generate_or_refuse(tmp_path, {"edge/m": b"char c\nchar s[4]\n"}, ["edge/m"], "accept")
