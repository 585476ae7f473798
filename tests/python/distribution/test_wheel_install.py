"""The binary wheel (scripts/build-wheel --prebuilt: the release build of the same sources CI
has just made, packed and repaired by auditwheel) carries a manylinux tag, installs into a
fresh venv from the wheel alone (its dependencies from PyPI), runs the smoke test of
install_smoke.py without anything of the checkout, and `pip uninstall` leaves nothing.
Not in the Debian package build (no network) nor under ASan/UBSan (it packs the release
build)."""

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest
from buildtree import REPO, not_under_sanitizers
from fresh_venv import DEPENDENCIES, LIMIT, FreshVenv, require_packaging_tools
from install_smoke import run_system, uninstall_leaves_nothing

import links_and_nodes

pytestmark = [
    pytest.mark.skipif(bool(os.environ.get("LN_PACKAGE_TESTS")),
                       reason="the Debian package build has no network for PyPI"),
    not_under_sanitizers("the wheel packs the release build"),
]


def build_wheel(out: Path) -> Path:
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}:{os.environ['PATH']}"}
    proc = subprocess.run(["bash", str(REPO / "scripts" / "build-wheel"), "--prebuilt",
                           "--out", str(out)], env=env, text=True, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, timeout=LIMIT)
    assert proc.returncode == 0, proc.stdout
    wheels = list(out.glob("*.whl"))
    assert len(wheels) == 1, wheels
    return wheels[0]


def test_wheel_installs_runs_and_uninstalls(tmp_path: Path) -> None:
    require_packaging_tools()
    wheel = build_wheel(tmp_path / "dist")
    # the version of the one place it lives (__version__, checked against ln.h elsewhere)
    tag = re.fullmatch(rf"links_and_nodes-{re.escape(links_and_nodes.__version__)}-py3-none-"
                       r"(manylinux_2_\d+_x86_64|manylinux_2_\d+_aarch64)\.whl", wheel.name)
    assert tag, wheel.name
    shown = subprocess.run([str(Path(sys.executable).parent / "auditwheel"), "show",
                            str(wheel)], text=True, capture_output=True, timeout=LIMIT)
    assert f'platform tag: "{tag.group(1)}"' in shown.stdout.replace("\n", " "), shown.stdout

    venv = FreshVenv.create(tmp_path)
    venv.pip("install", *DEPENDENCIES)
    before = venv.files()
    start = time.monotonic()
    venv.pip("install", "--no-index", "--find-links", str(wheel.parent), "links_and_nodes")
    first_topic = run_system(venv, start)
    print(f"{wheel.name}: {wheel.stat().st_size} bytes; pip install to the first sample "
          f"of topic echo: {first_topic:.1f} s")
    uninstall_leaves_nothing(venv, before)
