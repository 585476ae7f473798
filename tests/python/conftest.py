"""Shared setup of the Python tests: import the source tree, not an installed copy.

`ln_generate` lives at the repository root and `links_and_nodes` under `python/`;
both go first on sys.path so the tests run from a plain checkout, and so does this
directory, for the helpers every test package shares (polling.py).
"""

import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]

for _p in (REPO / "python", REPO, REPO / "tests" / "python"):
    if str(_p) not in sys.path:
        sys.path.insert(0, str(_p))
