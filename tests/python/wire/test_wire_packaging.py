"""The wire schemas ship with the Python package, since its codecs read them at import time:
pip's package-data (pyproject.toml) and `scons install` (python/SConscript, which the Debian
package python3-links-and-nodes is staged from) both install every *.schema file of
links_and_nodes/wire/."""

from __future__ import annotations

import fnmatch
import os
import subprocess
import sys
import tomllib
from pathlib import Path

REPO = Path(__file__).resolve().parents[3]
WIRE = REPO / "python" / "links_and_nodes" / "wire"


def test_pip_package_data_has_every_schema() -> None:
    config = tomllib.loads((REPO / "pyproject.toml").read_text())
    patterns = config["tool"]["setuptools"]["package-data"]["links_and_nodes.wire"]
    schemas = sorted(p.name for p in WIRE.glob("*.schema"))
    assert "daemon.schema" in schemas
    for name in schemas:
        assert any(fnmatch.fnmatch(name, pattern) for pattern in patterns), name


def test_scons_install_has_every_schema(tmp_path: Path) -> None:
    scons = Path(sys.executable).with_name("scons")
    command = [str(scons) if scons.exists() else "scons", "-n", "-Q", "install",
               f"DESTDIR={tmp_path}", "PREFIX=/usr"]
    out = subprocess.run(command, cwd=REPO, capture_output=True, text=True, timeout=300,
                         env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"})
    assert out.returncode == 0, out.stderr
    target = f"{tmp_path}/usr/lib/python3/dist-packages/links_and_nodes/wire"
    for schema in WIRE.glob("*.schema"):
        assert f'as "{target}/{schema.name}"' in out.stdout, schema.name
