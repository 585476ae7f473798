"""Where the manager keeps its runtime directory and how the instance lock behaves; pure
file-system tests, no manager process."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from links_and_nodes.manager.registry.runtime import InstanceLock, RuntimeDirError, prepare
from links_and_nodes.naming import runtime_dir


def test_runtime_dir_precedence() -> None:
    uid = os.getuid()
    assert runtime_dir("i", {"LN_RUNTIME_DIR": "/x/y", "XDG_RUNTIME_DIR": "/run/u"}) == Path(
        "/x/y")
    assert runtime_dir("i", {"XDG_RUNTIME_DIR": "/run/u"}) == Path("/run/u/ln/i")
    assert runtime_dir("i", {"LN_RUNTIME_DIR": "", "XDG_RUNTIME_DIR": ""}) == Path(
        f"/tmp/ln-{uid}/i")


def test_prepare_creates_private_directories(tmp_path: Path) -> None:
    os.chmod(tmp_path, 0o755)
    target = tmp_path / "xdg" / "ln" / "inst"
    assert prepare(target) == target
    for directory in (tmp_path / "xdg", tmp_path / "xdg" / "ln", target):
        assert stat.S_IMODE(directory.stat().st_mode) == 0o700
    assert stat.S_IMODE(tmp_path.stat().st_mode) == 0o755  # existing parents stay as they are


def test_prepare_tightens_an_existing_directory(tmp_path: Path) -> None:
    target = tmp_path / "run"
    target.mkdir(mode=0o777)
    os.chmod(target, 0o777)
    prepare(target)
    assert stat.S_IMODE(target.stat().st_mode) == 0o700


def test_prepare_refuses_a_file(tmp_path: Path) -> None:
    (tmp_path / "file").write_text("")
    with pytest.raises(RuntimeDirError, match="is not a directory"):
        prepare(tmp_path / "file")


def test_lock_is_exclusive_and_names_the_holder(tmp_path: Path) -> None:
    first = InstanceLock(tmp_path, "inst")
    first.acquire()
    assert (tmp_path / "manager.lock").read_text() == f"{os.getpid()}\n"
    second = InstanceLock(tmp_path, "inst")
    with pytest.raises(RuntimeDirError) as info:
        second.acquire()
    assert str(info.value) == (f"instance 'inst' is already managed by another ln_manager "
                               f"(pid {os.getpid()}, lock {tmp_path / 'manager.lock'})")
    first.release()
    with second:
        pass
