"""Building the Rust crates of rust/ from tests: cargo (missing_test_tool without it), the
environment that points them at this build's libln, and the safe crate's rlib that generated
Rust is compiled against."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest
from buildtree import REPO, SANITIZED, build_dir, missing_test_tool

WORKSPACE = REPO / "rust"
TARGET_DIR = REPO / "build" / "cargo-rust"
RELEASE = TARGET_DIR / "release"


def cargo() -> str:
    """The cargo command (PATH, else $CARGO_HOME/bin or ~/.cargo/bin)."""
    if os.environ.get("LN_PACKAGE_TESTS"):  # debian/rules builds with rust=no
        pytest.skip("the Debian package build builds no Rust crates (rust=no)")
    if SANITIZED:  # cargo and rustc would run with ASan preloaded, against its libln
        pytest.skip("not under ASan/UBSan: the crates build against the release libln; the "
                    "release run tests them")
    home = Path(os.environ.get("CARGO_HOME", Path.home() / ".cargo"))
    found = shutil.which("cargo") or shutil.which("cargo", path=str(home / "bin"))
    if found is None:
        missing_test_tool("cargo")
    return found


def cargo_env() -> dict[str, str]:
    """The environment of cargo and rustc: this build's libln, cargo's bin dir first."""
    env = dict(os.environ)
    env["LN_LIBRARY_PATH"] = str(build_dir() / "libln")
    env["PATH"] = os.pathsep.join([str(Path(cargo()).parent), env.get("PATH", "")])
    return env


def cargo_build(*args: str) -> None:
    """`cargo build --release ARGS` of the workspace, as SCons builds it (offline, locked);
    at once when up to date."""
    done = subprocess.run(
        [cargo(), "build", "--release", "--offline", "--locked", "-j", "2", "--quiet", *args,
         "--manifest-path", str(WORKSPACE / "Cargo.toml"), "--target-dir", str(TARGET_DIR)],
        capture_output=True, text=True, env=cargo_env(), timeout=900)
    assert done.returncode == 0, done.stderr


def rustc_check(source: Path) -> subprocess.CompletedProcess[str]:
    """Type-checks `source` as a library crate against the links_and_nodes rlib (built
    first), without code generation: const assertions are evaluated, nothing is linked."""
    cargo_build("-p", "links-and-nodes")
    rustc = Path(cargo()).parent / "rustc"
    return subprocess.run(
        [str(rustc) if rustc.exists() else "rustc", "--edition", "2021", "--crate-type", "lib",
         "--emit", "metadata", "-D", "warnings", "-o", str(source.with_suffix(".rmeta")),
         "--extern", f"links_and_nodes={RELEASE / 'liblinks_and_nodes.rlib'}",
         "-L", f"dependency={RELEASE / 'deps'}", str(source)],
        capture_output=True, text=True, env=cargo_env(), timeout=600)
