"""python-ndn, the independent NDN implementation the interop tests use (PyPI python-ndn,
requirements-dev.txt; never a dependency of the product): imported here, or the test
fails in CI / skips elsewhere (buildtree.missing_test_tool)."""

from __future__ import annotations

from typing import Any

import pytest
from buildtree import SANITIZED, missing_test_tool


def ndn() -> Any:
    """The python-ndn package (`ndn`), or the missing tool's failure/skip."""
    if SANITIZED:  # before any import: the process would abort in it
        pytest.skip("not under ASan/UBSan: python-ndn's pycryptodomex opens its SHA-256 with "
                    "RTLD_DEEPBIND, which the sanitizer runtime refuses")
    try:
        import ndn.app  # noqa: F401
        import ndn.encoding  # noqa: F401
        import ndn.security  # noqa: F401
        import ndn.transport.udp_face  # noqa: F401
    except ImportError:
        missing_test_tool("the Python package ndn (python-ndn, requirements-dev.txt)")
    import ndn as package

    return package
