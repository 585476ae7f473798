"""`cargo package` of the Rust crates (not published): the sys crate packs and its tarball
builds (verified, against this build's libln); the safe crate packs (its dependency on the
sys crate exists on no registry, so it is packed without verification or lock file) and both
list their sources, readme and metadata."""

from __future__ import annotations

import subprocess
import tomllib
from pathlib import Path

import pytest
from buildtree import REPO, not_under_sanitizers
from cargo_build import WORKSPACE, cargo, cargo_env

pytestmark = not_under_sanitizers(
    "the Rust programs link the release libln of build/cargo-rust (cargo builds against one "
    "libln); the release run tests them")

CRATES = ["links-and-nodes-sys", "links-and-nodes"]


def package(tmp_path: Path, *args: str) -> subprocess.CompletedProcess[str]:
    env = cargo_env()
    env["LN_INCLUDE_DIR"] = str(REPO / "libln" / "include")
    return subprocess.run(
        [cargo(), "package", "--offline", "--allow-dirty", "-j", "2", *args,
         "--manifest-path", str(WORKSPACE / "Cargo.toml"), "--target-dir", str(tmp_path)],
        capture_output=True, text=True, env=env, timeout=600)


@pytest.mark.parametrize("crate", CRATES)
def test_package_lists_sources_and_readme(crate: str, tmp_path: Path) -> None:
    done = package(tmp_path, "-p", crate, "--list")
    assert done.returncode == 0, done.stderr
    files = done.stdout.split()
    assert {"Cargo.toml", "src/lib.rs", "rust.md"} <= set(files), files
    manifest = tomllib.loads((WORKSPACE / crate / "Cargo.toml").read_text())["package"]
    assert manifest["description"] and manifest["license"] == {"workspace": True}
    assert manifest["readme"] == {"workspace": True}


def test_sys_crate_packages_and_verifies(tmp_path: Path) -> None:
    done = package(tmp_path, "-p", "links-and-nodes-sys")
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "package" / "links-and-nodes-sys-0.1.0.crate").is_file()


def test_safe_crate_packages(tmp_path: Path) -> None:
    done = package(tmp_path, "-p", "links-and-nodes", "--no-verify", "--exclude-lockfile")
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "package" / "links-and-nodes-0.1.0.crate").is_file()
