"""Lookup of md names: directory order, LN_MESSAGE_DEFINITION_DIRS, and --print-deps."""

from __future__ import annotations

from pathlib import Path

import pytest

from ln_generate import MdRegistry, default_md_dirs
from ln_generate.cli import main
from ln_generate.lookup import ENV_DIRS, builtin_md_dir

REPO = Path(__file__).resolve().parents[3]


def put(root: Path, name: str, text: str) -> Path:
    path = root / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def test_builtin_dir_is_the_source_tree_one() -> None:
    assert builtin_md_dir() == REPO / "message_definitions"


def test_order_explicit_then_builtin_then_env(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    env_dir, explicit = tmp_path / "env", tmp_path / "explicit"
    put(env_dir, "ln/string", "double shadowed\n")
    put(env_dir, "only/in_env", "int a\n")
    put(explicit, "ln/time", "double overridden\n")
    monkeypatch.setenv(ENV_DIRS, f"{env_dir}:{tmp_path / 'missing'}")
    dirs = default_md_dirs([str(explicit)])
    assert dirs[:2] == [explicit, REPO / "message_definitions"]
    assert dirs[2:] == [env_dir, tmp_path / "missing"]
    reg = MdRegistry(dirs)
    assert [f.name for f in reg.load("ln/time").struct.fields] == ["overridden"]
    assert [f.name for f in reg.load("ln/string").struct.fields] == ["data"]  # built-in wins
    assert reg.load("only/in_env").path == env_dir / "only/in_env"


def test_imports_use_the_same_lookup(tmp_path: Path) -> None:
    put(tmp_path, "a/b", 'define s as "ln/string"\ns* names\n')
    md = MdRegistry(default_md_dirs([str(tmp_path)])).load("a/b")
    assert md.imports["s"].path == REPO / "message_definitions/ln/string"


def test_print_deps_lists_every_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--print-deps", "robot/plan_path", "robot/tool_state"]) == 0
    listed = capsys.readouterr().out.split()
    md = REPO / "message_definitions"
    assert sorted(listed) == sorted(
        str(md / n) for n in ["robot/plan_path", "robot/joint_state", "ln/string",
                              "robot/tool_state", "robot/pose"]
    )


def test_directory_named_like_an_md_is_not_an_md(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "robot").mkdir()
    assert main(["-o", str(tmp_path / "x.h"), "--md-dir", str(tmp_path), "robot"]) == 1
    assert "message definition 'robot' not found" in capsys.readouterr().err
