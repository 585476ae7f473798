"""Generated files are written atomically, only when changed, and match golden copies.

Golden files live in tests/golden/; after an intended change of the emitters run
`LN_UPDATE_GOLDEN=1 pytest tests/python/md/test_generate_output.py` and review the diff.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from ln_generate.cli import main

GOLDEN = Path(__file__).resolve().parents[2] / "golden"
GOLDEN_SETS = {
    "joint_state": ["robot/joint_state"],
    "tool_state": ["robot/tool_state"],
    "plan_path": ["robot/plan_path"],
    "fault_event": ["robot/fault_event"],
}


@pytest.mark.parametrize("suffix", ["h", "hpp", "py"])
@pytest.mark.parametrize("stem", sorted(GOLDEN_SETS))
def test_golden(stem: str, suffix: str, tmp_path: Path) -> None:
    out = tmp_path / f"{stem}.{suffix}"
    assert main(["-o", str(out), *GOLDEN_SETS[stem]]) == 0
    golden = GOLDEN / f"{stem}.{suffix}"
    if os.environ.get("LN_UPDATE_GOLDEN"):
        assert not os.environ.get("CI"), "LN_UPDATE_GOLDEN must not be set in CI"
        golden.parent.mkdir(exist_ok=True)
        golden.write_bytes(out.read_bytes())
        pytest.skip("golden file updated: review the diff and run again without LN_UPDATE_GOLDEN")
    assert out.read_text() == golden.read_text()


def test_unchanged_output_is_not_rewritten(tmp_path: Path) -> None:
    out = tmp_path / "m.h"
    assert main(["-o", str(out), "robot/joint_state"]) == 0
    stat = out.stat()
    os.utime(out, ns=(stat.st_atime_ns, stat.st_mtime_ns - 10**9))
    old = out.stat()
    assert main(["-o", str(out), "robot/joint_state"]) == 0
    assert out.stat().st_mtime_ns == old.st_mtime_ns and out.stat().st_ino == old.st_ino
    assert main(["-o", str(out), "robot/joint_state", "robot/command"]) == 0
    assert out.stat().st_ino != old.st_ino  # replaced by rename, never written in place
    assert "robot_command_t" in out.read_text()
    assert [p.name for p in tmp_path.iterdir()] == ["m.h"]  # no temporary left behind


def test_lang_flag_overrides_suffix(tmp_path: Path) -> None:
    out = tmp_path / "types.txt"
    assert main(["-o", str(out), "--lang", "cpp", "robot/pose"]) == 0
    assert "namespace robot {" in out.read_text()


def test_dependencies_come_first_and_once(tmp_path: Path) -> None:
    out = tmp_path / "m.h"
    assert main(["-o", str(out), "robot/plan_path", "robot/joint_state"]) == 0
    text = out.read_text()
    assert text.count("typedef struct robot_joint_state {") == 1
    assert text.index("robot_joint_state_t;") < text.index("robot_plan_path_response_t;")
    assert text.index("} ln_string_t;") < text.index("} robot_plan_path_request_t;")
