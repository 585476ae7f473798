"""The lossy pull tests run in the multi-host system of the network tests (hosts a, b, c
and mgr, tests/python/network/conftest.py): the same fixture, so that they skip or fail
exactly where those do."""

from __future__ import annotations

from network.conftest import system  # noqa: F401 - the fixture, shared
