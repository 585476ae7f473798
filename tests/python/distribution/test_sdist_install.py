"""The sdist (`python -m build --sdist` of the checkout) installs into a fresh venv with a C
compiler: pip builds the native parts with SCons from PyPI (build_backend/), from scratch, into
the same layout as the wheel; then the smoke test of install_smoke.py, and `pip uninstall`
leaves nothing.  Not in the Debian package build (no network) nor under ASan/UBSan."""

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
from buildtree import REPO, not_under_sanitizers
from fresh_venv import DEPENDENCIES, LIMIT, FreshVenv, packaging_lock, require_packaging_tools
from install_smoke import run_system, uninstall_leaves_nothing

import links_and_nodes

pytestmark = [
    pytest.mark.skipif(bool(os.environ.get("LN_PACKAGE_TESTS")),
                       reason="the Debian package build has no network for PyPI"),
    not_under_sanitizers("pip builds the release flavour"),
]


def build_sdist(out: Path) -> Path:
    with packaging_lock():
        proc = subprocess.run([sys.executable, "-m", "build", "--sdist", "--outdir", str(out),
                               str(REPO)], text=True, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, timeout=LIMIT)
    assert proc.returncode == 0, proc.stdout
    sdists = list(out.glob("links_and_nodes-*.tar.gz"))
    assert [s.name for s in sdists] == [f"links_and_nodes-{links_and_nodes.__version__}.tar.gz"]
    return sdists[0]


def test_sdist_builds_installs_runs_and_uninstalls(tmp_path: Path) -> None:
    require_packaging_tools()
    sdist = build_sdist(tmp_path / "dist")
    venv = FreshVenv.create(tmp_path)
    venv.pip("install", *DEPENDENCIES)
    before = venv.files()
    venv.env["LN_BUILD_JOBS"] = "2"
    start = time.monotonic()
    venv.pip("install", str(sdist))
    del venv.env["LN_BUILD_JOBS"]
    print(f"{sdist.name}: pip install (building the C parts) to the first sample of topic "
          f"echo: {run_system(venv, start):.1f} s")
    uninstall_leaves_nothing(venv, before)
