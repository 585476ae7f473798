"""The version of the Links and Nodes configuration language this reader implements.

`requires_version X.Y.Z` in a `.lnc` file is compared with LANGUAGE_VERSION, not with the
Python package's version: files written for the original Links and Nodes state the
version of its language they need (robotkernel's include files say 0.2.43).
"""

from __future__ import annotations

import re

# The original's 2.x line: the language of its 2.8 releases, which every file written for
# 0.2.x and later 2.x reads the same under.
LANGUAGE_VERSION = "2.8.0"
_VERSION_RE = re.compile(r"[0-9]+(\.[0-9]+)*\Z")


def parse_version(text: str) -> tuple[int, ...] | None:
    """`2.8.0` -> (2, 8, 0), padded so that 2.8 == 2.8.0; None if it is not a version."""
    if not _VERSION_RE.match(text):
        return None
    parts = [int(x) for x in text.split(".")]
    return tuple(parts + [0] * (3 - len(parts)))
