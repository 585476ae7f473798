"""python-ndn, the independent NDN implementation the interop tests use (PyPI python-ndn,
requirements-dev.txt; never a dependency of the product): imported here, or the test
fails in CI / skips elsewhere (buildtree.missing_test_tool)."""

from __future__ import annotations

from typing import Any

from buildtree import missing_test_tool


def ndn() -> Any:
    """The python-ndn package (`ndn`), or the missing tool's failure/skip."""
    try:
        import ndn.app  # noqa: F401
        import ndn.encoding  # noqa: F401
        import ndn.security  # noqa: F401
        import ndn.transport.udp_face  # noqa: F401
    except ImportError:
        missing_test_tool("the Python package ndn (python-ndn, requirements-dev.txt)")
    import ndn as package

    return package
