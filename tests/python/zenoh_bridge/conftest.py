"""The fixture of the Zenoh bridge tests (the helpers are in zenoh_sites.py): two sites in
network namespaces, torn down with everything started in them, once with the bridges' topic
samples through the native core (`--native on`) and once through Python (`--native off`).
This directory has no __init__.py: a package named `zenoh` would hide the real one."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from netlab import NetLab
from zenoh_sites import Site, require_native_core, require_zenoh


@pytest.fixture(params=["native", "python"])
def sites(netlab: NetLab, request: pytest.FixtureRequest) -> Iterator[tuple[Site, Site]]:
    """Sites a (host a, 10.77.0.1) and b (host b, 10.77.0.2); nothing started yet.  Their
    bridges carry topic samples through the native core or through Python (the param)."""
    require_zenoh()
    native = request.param == "native"
    if native:
        require_native_core()
    a, b = (Site(netlab, netlab[h], h, native=native) for h in ("a", "b"))
    try:
        yield a, b
    finally:
        b.close()
        a.close()
