"""Fixtures of the MATLAB/Octave client tests (docs/matlab.md): the private manager of the
topic tests, knowing the test mds of tests/fixtures/md/matlab, and `octave`, which runs an
Octave script against it with octave-cli and the MEX client of the build tree."""

from __future__ import annotations

import os
import shutil
import subprocess
from collections.abc import Callable
from pathlib import Path

import pytest
from buildtree import REPO, build_dir, missing_test_tool
from topics.conftest import TOOLS, Manager, manager, wait_ready  # noqa: F401 - fixture

import links_and_nodes as ln

MDS = REPO / "tests" / "fixtures" / "md" / "matlab"
SCRIPTS = Path(__file__).resolve().parent / "octave"
LIMIT = 120.0  # an upper bound for one Octave run, never a measurement

ln.add_message_definition_dir(MDS)

Octave = Callable[..., subprocess.CompletedProcess[str]]


@pytest.fixture(autouse=True)
def _test_mds(monkeypatch: pytest.MonkeyPatch) -> None:
    """The manager (started after this) finds the test mds through its environment."""
    dirs = [str(MDS)] + [d for d in os.environ.get("LN_MESSAGE_DEFINITION_DIRS", "").split(
        os.pathsep) if d]
    monkeypatch.setenv("LN_MESSAGE_DEFINITION_DIRS", os.pathsep.join(dirs))


def octave_cli() -> str:
    exe = shutil.which("octave-cli")
    if exe is None:
        missing_test_tool("GNU Octave (octave-cli; scripts/setup installs octave and "
                          "liboctave-dev)")
    mex = build_dir() / "matlab" / "ln_mex.mex"
    if not mex.exists():
        pytest.fail(f"{mex} is missing: run scons (matlab=1 builds it with mkoctfile)")
    return exe


@pytest.fixture
def octave(manager: Manager) -> Octave:  # noqa: F811 - the fixture imported above
    """run(script, check=True): runs Octave code against the test's manager; with check, a
    failing script fails the test with Octave's output."""
    exe = octave_cli()

    def run(script: str, check: bool = True) -> subprocess.CompletedProcess[str]:
        prelude = f"addpath('{build_dir() / 'matlab'}'); addpath('{SCRIPTS}'); "
        done = subprocess.run([exe, "--no-gui", "--norc", "--quiet", "--eval",
                               prelude + script],
                              env={**manager.env, "LN_MANAGER": manager.address},
                              capture_output=True, text=True, timeout=LIMIT)
        if check:
            assert done.returncode == 0, f"octave failed:\n{done.stdout}\n{done.stderr}"
        return done

    return run
