"""The fixture of the Zenoh bridge tests (the helpers are in zenoh_sites.py): two sites in
network namespaces, torn down with everything started in them, once with the bridges' topic
samples through the native core (`--native on`) and once through Python (`--native off`).
This directory has no __init__.py: a package named `zenoh` would hide the real one."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from netlab import NetLab
from zenoh_sites import Site, site_pair


@pytest.fixture(params=["native", "python"])
def sites(netlab: NetLab, request: pytest.FixtureRequest) -> Iterator[tuple[Site, Site]]:
    """site_pair through the native core or through Python (the param)."""
    yield from site_pair(netlab, request.param == "native")
