"""Which build the end-to-end tests run: the programs of build/release, or of the SCons variant
directory in $LN_BUILD_DIR (scripts/test-sanitized-python points it at the ASan/UBSan build and
sets LN_SANITIZED), and a skip marker that applies only to that sanitizer run."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SANITIZED = bool(os.environ.get("LN_SANITIZED"))


def build_dir() -> Path:
    """The variant directory whose libln tools, examples and daemon the tests start."""
    override = os.environ.get("LN_BUILD_DIR")
    return Path(override) if override else REPO / "build" / "release"


def not_under_sanitizers(reason: str) -> pytest.MarkDecorator:
    """Skip a test in the sanitizer run only, saying why; the normal run always runs it."""
    return pytest.mark.skipif(SANITIZED, reason=f"not under ASan/UBSan: {reason}")
