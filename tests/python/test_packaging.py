"""The packaging metadata agrees with the code: one version in ln.h, the Python package and
debian/changelog; pyproject.toml installs every folder of message_definitions/; and
debian/libln1.symbols lists exactly what libln exports (needs the built library; skipped
without it only outside CI, where it must fail)."""

import os
import re
import subprocess
import tomllib
from pathlib import Path

import pytest

import links_and_nodes

REPO = Path(__file__).resolve().parents[2]
LIBLN = REPO / "build" / "release" / "libln" / "libln.so.1"


def header_version() -> str:
    text = (REPO / "libln" / "include" / "ln" / "ln.h").read_text()
    found = dict(re.findall(r"^#define LN_VERSION_(MAJOR|MINOR|PATCH) (\d+)$", text, re.M))
    return f"{found['MAJOR']}.{found['MINOR']}.{found['PATCH']}"


def test_versions_agree() -> None:
    changelog = (REPO / "debian" / "changelog").read_text().splitlines()[0]
    match = re.match(r"links-and-nodes \(([^)]+)\) ", changelog)
    assert match, changelog
    assert header_version() == links_and_nodes.__version__ == match.group(1)


def test_pip_installs_every_message_definition_folder() -> None:
    pyproject = tomllib.loads((REPO / "pyproject.toml").read_text())
    data_files = pyproject["tool"]["setuptools"]["data-files"]
    md_root = REPO / "message_definitions"
    folders = sorted(p.name for p in md_root.iterdir()
                     if p.is_dir() and not p.name.startswith("."))
    # Only one level: a nested folder would need its own entry, so it must not appear.
    assert not [p for p in md_root.glob("*/*") if p.is_dir()]
    assert data_files == {f"share/links_and_nodes/message_definitions/{f}":
                          [f"message_definitions/{f}/*"] for f in folders}


def test_symbols_file_lists_exactly_the_exports() -> None:
    if not LIBLN.exists():
        if os.environ.get("CI"):
            pytest.fail(f"{LIBLN} is not built")
        pytest.skip(f"{LIBLN} is not built")
    out = subprocess.run(["nm", "-D", "--defined-only", str(LIBLN)], capture_output=True,
                         text=True, check=True).stdout
    exported = sorted(line.split()[-1] for line in out.splitlines() if line.strip())
    symbols_file = (REPO / "debian" / "libln1.symbols").read_text().splitlines()
    listed = sorted(line.split()[0].split("@")[0] for line in symbols_file
                    if line.startswith(" "))
    assert listed == exported, "debian/libln1.symbols is out of date: add new symbols " \
                               "with the version that introduces them"
