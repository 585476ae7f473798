"""Which build the end-to-end tests run: the programs of build/release, or of the SCons variant
directory in $LN_BUILD_DIR (scripts/test-sanitized-python points it at the ASan/UBSan build and
sets LN_SANITIZED), a skip marker that applies only to that sanitizer run, and what a test
does when a test-only tool is missing."""

from __future__ import annotations

import os
from pathlib import Path
from typing import NoReturn

import pytest

REPO = Path(__file__).resolve().parents[2]
SANITIZED = bool(os.environ.get("LN_SANITIZED"))


def missing_test_tool(what: str) -> NoReturn:
    """A tool only the tests use (a PyPI or npm package, never a dependency of the product)
    is not installed: a failure in CI's run from the checkout (CI set, scripts/setup
    installs them), a skip elsewhere, also in the Debian package build's test run
    (LN_PACKAGE_TESTS set), which has Debian's packages only."""
    if os.environ.get("CI") and not os.environ.get("LN_PACKAGE_TESTS"):
        pytest.fail(f"{what} is missing (scripts/setup installs it)")
    pytest.skip(f"{what} is not installed")


def build_dir() -> Path:
    """The variant directory whose libln tools, examples and daemon the tests start."""
    override = os.environ.get("LN_BUILD_DIR")
    return Path(override) if override else REPO / "build" / "release"


def not_under_sanitizers(reason: str) -> pytest.MarkDecorator:
    """Skip a test in the sanitizer run only, saying why; the normal run always runs it."""
    return pytest.mark.skipif(SANITIZED, reason=f"not under ASan/UBSan: {reason}")
