"""The fixture of the Zenoh bridge tests (the helpers are in zenoh_sites.py): two sites in
network namespaces, torn down with everything started in them.  This directory has no
__init__.py: a package named `zenoh` would hide the real one."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from zenoh_sites import Site, require_zenoh

from netlab import NetLab


@pytest.fixture
def sites(netlab: NetLab) -> Iterator[tuple[Site, Site]]:
    """Sites a (host a, 10.77.0.1) and b (host b, 10.77.0.2); nothing started yet."""
    require_zenoh()
    a, b = Site(netlab, netlab["a"], "a"), Site(netlab, netlab["b"], "b")
    try:
        yield a, b
    finally:
        b.close()
        a.close()
