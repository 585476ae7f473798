"""Fixtures of the waitset tests: the private manager of the topic tests (unique instance,
free port, log in a file; every segment of the instance gone at the end)."""

from __future__ import annotations

from topics.conftest import manager  # noqa: F401 - fixture
