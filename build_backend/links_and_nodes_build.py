"""The PEP 517 backend of pyproject.toml: setuptools' own, plus the native parts for wheels.
build_wheel first has SCons build libln, libln_pull, libln_admin.so and ln_daemon (zenoh_core
and rust off; in a checkout also uPlot, with npm) in build/release of the source tree, or
takes an already built variant directory from $LN_NATIVE_BUILD_DIR (scripts/build-wheel,
after running SCons itself); setup.py then copies them into the wheel.  Editable installs,
and wheels asked for with `-C native=no` or $LN_PYTHON_ONLY=1 (the bindings beside an
installed libln, e.g. Debian's), stay Python-only and need no SCons (docs/install.md)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from typing import Any

from setuptools import build_meta as _setuptools
from setuptools.build_meta import (  # noqa: F401  (the hooks taken over as they are)
    build_editable,
    build_sdist,
    get_requires_for_build_editable,
    get_requires_for_build_sdist,
    prepare_metadata_for_build_editable,
    prepare_metadata_for_build_wheel,
)

NATIVE_DIR = "LN_NATIVE_BUILD_DIR"  # read by setup.py too
# Where an sdist carries uPlot (setup.py); a checkout has it in build/webui/uplot once built.
VENDOR = "python/links_and_nodes/manager/frontends/webui/static/vendor"
# What a wheel carries from a SCons variant directory (relative to it).
TARGETS = ["libln/libln.so.1.0.0", "libln/links_and_nodes/libln_admin.so",
           "libln_pull/libln_pull.so.1.0.0", "ln_daemon/ln_daemon"]


def _scons_build(source: Path) -> Path:
    """build/release of `source` with the wheel's native parts built, by SCons from PyPI."""
    variant = source / "build" / "release"
    jobs = os.environ.get("LN_BUILD_JOBS") or str(os.cpu_count() or 1)
    cmd = [sys.executable, "-m", "SCons", "-j", jobs, "zenoh_core=no", "rust=no"]
    cmd += [str(variant / t) for t in TARGETS]
    if not (source / VENDOR / "uPlot.iife.min.js").is_file() \
            or not (source / VENDOR / "dagre.min.js").is_file():
        cmd.append(str(source / "build" / "webui"))  # a checkout: uPlot, dagre with npm
    print("links_and_nodes: building the native parts: " + " ".join(cmd), flush=True)
    # SCons writes its progress to stdout, which pip reserves for the hook's protocol.
    subprocess.run(cmd, cwd=source, check=True, stdout=sys.stderr)
    return variant


def python_only(config_settings: dict[str, Any] | None) -> bool:
    """A wheel without the native parts: `-C native=no` or $LN_PYTHON_ONLY=1."""
    return ((config_settings or {}).get("native") == "no"
            or os.environ.get("LN_PYTHON_ONLY") == "1")


def get_requires_for_build_wheel(config_settings: dict[str, Any] | None = None) -> list[str]:
    extra = [] if python_only(config_settings) else ["scons>=4.4"]
    return _setuptools.get_requires_for_build_wheel(config_settings) + extra


def build_wheel(wheel_directory: str, config_settings: dict[str, Any] | None = None,
                metadata_directory: str | None = None) -> str:
    if python_only(config_settings):
        os.environ.pop(NATIVE_DIR, None)
        return _setuptools.build_wheel(wheel_directory, config_settings, metadata_directory)
    given = os.environ.get(NATIVE_DIR)
    variant = Path(given).resolve() if given else _scons_build(Path.cwd())
    missing = [t for t in TARGETS if not (variant / t).is_file()]
    if missing:
        raise RuntimeError(f"{variant}: no {', '.join(missing)} (build them with scons)")
    os.environ[NATIVE_DIR] = str(variant)
    try:
        return _setuptools.build_wheel(wheel_directory, config_settings, metadata_directory)
    finally:
        if given is None:
            del os.environ[NATIVE_DIR]
        else:
            os.environ[NATIVE_DIR] = given
