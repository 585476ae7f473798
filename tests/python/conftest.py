"""Shared setup of the Python tests: import the source tree, not an installed copy.

`ln_generate` lives at the repository root and `links_and_nodes` under `python/`;
both go first on sys.path so the tests run from a plain checkout, and so does this
directory, for the helpers every test package shares (polling.py, netlab.py).
The `netlab` fixture is here so that any test can ask for emulated hosts.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from netlab import NetLab

REPO = Path(__file__).resolve().parents[2]

for _p in (REPO / "python", REPO, REPO / "tests" / "python"):
    if str(_p) not in sys.path:
        sys.path.insert(0, str(_p))


@pytest.fixture
def netlab(tmp_path: Path) -> Iterator[NetLab]:
    """A NetLab with hosts a (10.77.0.1) and b (10.77.0.2), logs in tmp_path/netlab; add more
    with add_host().  Skips, saying why, where network namespaces cannot be made (fails
    instead under CI=1).  Torn down, with everything in it, after the test."""
    import netlab as netlab_module

    netlab_module.require_netlab()
    with netlab_module.NetLab(tmp_path / "netlab") as lab:
        yield lab
