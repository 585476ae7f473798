"""scripts/stack-chain, the static worst-case stack of a build from GCC's -fcallgraph-info=su
call graphs (docs/pull.md, "Sizes"), on call graphs written here in GCC's .ci format: the
worst chain across files, callbacks and library helpers counted only as stated, and the
failures (recursion, an unknown callee, an unbounded frame, a bad root)."""

from __future__ import annotations

import importlib.machinery
import importlib.util
import json
import sys
import types
from pathlib import Path

import pytest
from buildtree import REPO


def _load() -> types.ModuleType:
    path = str(REPO / "scripts" / "stack-chain")
    loader = importlib.machinery.SourceFileLoader("stack_chain", path)
    spec = importlib.util.spec_from_loader("stack_chain", loader)
    assert spec is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["stack_chain"] = module  # its dataclasses look themselves up there
    loader.exec_module(module)
    return module


stack_chain = _load()


def node(title: str, frame: int | None = None, kind: str = "static") -> str:
    name = title.split(":")[-1]
    if frame is None:
        return f'node: {{ title: "{title}" label: "{name}\\n<built-in>" shape : ellipse }}'
    return f'node: {{ title: "{title}" label: "{name}\\na.c:1:1\\n{frame} bytes ({kind})" }}'


def edge(a: str, b: str) -> str:
    return f'edge: {{ sourcename: "{a}" targetname: "{b}" }}'


def write(path: Path, *lines: str) -> Path:
    path.write_text(f'graph: {{ title: "{path.name}"\n' + "\n".join(lines) + "\n}\n")
    return path


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = stack_chain.main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def test_worst_chain_across_files(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    write(
        tmp_path / "a.ci",
        node("root", 40),
        node("a.c:helper", 16),
        node("leaf"),
        node("memcpy"),
        edge("root", "a.c:helper"),
        edge("root", "leaf"),
        edge("a.c:helper", "memcpy"),
    )
    write(tmp_path / "b.ci", node("leaf", 100), node("b.c:helper", 8), edge("leaf", "b.c:helper"))
    out_json = tmp_path / "out.json"
    code, out, _ = run(
        capsys, "--roots", "root", str(tmp_path), "--extern", "memcpy=24", "--json", str(out_json)
    )
    assert code == 0
    assert "root: 148 bytes: root 40 -> leaf 100 -> helper 8" in out
    result = json.loads(out_json.read_text())
    assert result["worst_bytes"] == 148 and result["externs"] == {"memcpy": 24}


def test_callbacks_and_helpers_count_only_as_stated(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    ci = write(
        tmp_path / "a.ci",
        node("f", 32),
        node("__indirect_call"),
        node("__aeabi_uidiv"),
        edge("f", "__indirect_call"),
        edge("f", "__aeabi_uidiv"),
    )
    code, _, err = run(capsys, "--roots", "f", str(ci), "--default-externs")
    assert code == 1 and "--callback-budget" in err
    code, _, err = run(capsys, "--roots", "f", str(ci), "--callback-budget", "0")
    assert code == 1 and "__aeabi_uidiv" in err
    code, out, _ = run(
        capsys, "--roots", "f", str(ci), "--callback-budget", "100", "--default-externs"
    )
    assert code == 0 and "f: 132 bytes" in out and "indirect calls counted as 100" in out


@pytest.mark.parametrize("case", ["recursion", "dynamic", "root"])
def test_unbounded_chains_fail(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], case: str
) -> None:
    lines = {
        "recursion": [node("f", 8), node("a.c:g", 8), edge("f", "a.c:g"), edge("a.c:g", "f")],
        "dynamic": [node("f", 8, "dynamic")],
        "root": [node("g", 8)],
    }[case]
    code, _, err = run(capsys, "--roots", "f", str(write(tmp_path / "a.ci", *lines)))
    assert code == 1
    assert {
        "recursion": "recursion: f -> g -> f",
        "dynamic": "unbounded dynamic size",
        "root": "root f: not found",
    }[case] in err


def test_bounded_dynamic_frames_count(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    ci = write(tmp_path / "a.ci", node("f", 72, "dynamic,bounded"))
    assert run(capsys, "--roots", "f", str(ci))[:2] == (
        0,
        "f: 72 bytes: f 72\nworst: f: 72 bytes\n",
    )
