"""A virtual environment of its own for testing an installed links_and_nodes (wheel or sdist):
created by the interpreter running the tests, used with an environment that hides the
checkout (no PYTHONPATH, no LN_* paths, not the checkout's .venv on PATH, a temporary working
directory and HOME), and the list of its files, to check that `pip uninstall` leaves nothing
behind.  Skips (missing_test_tool) only without the packaging tools of requirements-dev.txt."""

from __future__ import annotations

import contextlib
import fcntl
import importlib.util
import os
import shutil
import subprocess
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from buildtree import REPO, missing_test_tool

LIMIT = 900  # seconds for one command (an sdist builds the C parts); never a measurement
# What reaches PyPI and the compiler from the caller's environment, nothing of the checkout.
PASS_THROUGH = ("http_proxy", "https_proxy", "no_proxy", "HTTP_PROXY", "HTTPS_PROXY",
                "NO_PROXY", "PIP_INDEX_URL", "PIP_EXTRA_INDEX_URL", "PIP_TRUSTED_HOST",
                "PIP_CERT", "SSL_CERT_FILE", "REQUESTS_CA_BUNDLE", "TMPDIR", "LANG", "CC", "CXX")
DEPENDENCIES = ["numpy>=1.24", "zstandard>=0.20", "lz4>=4.0"]  # pyproject.toml's


def require_packaging_tools() -> None:
    """build, auditwheel and patchelf (scripts/build-wheel), and a C compiler."""
    if importlib.util.find_spec("build") is None:
        missing_test_tool("build (PyPI)")
    for tool in ("auditwheel", "patchelf"):
        if shutil.which(tool, path=f"{Path(sys.executable).parent}:{os.environ['PATH']}") \
                is None:
            missing_test_tool(f"{tool} (PyPI)")
    if shutil.which("cc") is None:
        missing_test_tool("a C compiler (cc)")


@dataclass
class FreshVenv:
    root: Path
    work: Path
    env: dict[str, str]

    @classmethod
    def create(cls, tmp: Path) -> FreshVenv:
        root, work, home = tmp / "venv", tmp / "work", tmp / "home"
        work.mkdir()
        home.mkdir()
        subprocess.run([sys.executable, "-m", "venv", str(root)], check=True, timeout=LIMIT)
        env = {k: os.environ[k] for k in PASS_THROUGH if k in os.environ}
        env.update(PATH=f"{root / 'bin'}:/usr/bin:/bin", HOME=str(home),
                   PIP_DISABLE_PIP_VERSION_CHECK="1",
                   # downloads stay cached between runs (HOME is new each time)
                   PIP_CACHE_DIR=os.environ.get("PIP_CACHE_DIR",
                                                str(Path.home() / ".cache" / "pip")))
        return cls(root, work, env)

    @property
    def python(self) -> str:
        return str(self.root / "bin" / "python")

    def run(self, *argv: str, env: dict[str, str] | None = None) -> str:
        """argv in the venv's environment, from its working directory; its output (stdout
        and stderr), or a failure that shows it."""
        proc = subprocess.run(argv, cwd=self.work, env=env or self.env, text=True,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              stdin=subprocess.DEVNULL, timeout=LIMIT)
        assert proc.returncode == 0, f"{' '.join(argv)}: exit {proc.returncode}\n{proc.stdout}"
        return proc.stdout

    def pip(self, *args: str) -> str:
        return self.run(self.python, "-m", "pip", *args)

    def files(self) -> set[str]:
        """Every file (and symlink) in the venv, relative to it.  Directories are left out:
        pip leaves the emptied directories of data files (share/links_and_nodes/...)."""
        return {str(p.relative_to(self.root)) for p in self.root.rglob("*")
                if p.is_symlink() or not p.is_dir()}

    def installed_files(self, dist: str) -> list[Path]:
        """The files pip lists for `dist` (its RECORD), as absolute paths."""
        out = self.pip("show", "-f", dist)
        location = Path(next(line.split(": ", 1)[1] for line in out.splitlines()
                             if line.startswith("Location: ")))
        listed = out.split("Files:\n", 1)[1].splitlines()
        return [(location / line.strip()).resolve() for line in listed if line.strip()]


def outside_checkout(paths: dict[str, str]) -> None:
    """Every path in `paths` (what, path) lies outside the checkout."""
    inside = {what: p for what, p in paths.items() if Path(p).resolve().is_relative_to(REPO)}
    assert not inside, f"the checkout is used: {inside}"


@contextlib.contextmanager
def packaging_lock() -> Iterator[None]:
    """The lock scripts/build-wheel takes: setuptools writes links_and_nodes.egg-info into
    the checkout, so two builds of the same checkout must not overlap."""
    (REPO / "build").mkdir(exist_ok=True)
    with open(REPO / "build" / "packaging.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        yield
