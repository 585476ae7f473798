"""MANIFEST.in puts into the sdist every SConscript of the checkout (SCons reads them all,
whatever it builds), so `pip install` of the sdist can run the SConstruct."""

import re
from pathlib import Path

from buildtree import REPO

SKIP = {"build", ".venv", "target", "dist"}


def test_every_sconscript_is_in_the_sdist() -> None:
    text = (REPO / "MANIFEST.in").read_text()
    grafted = [Path(d) for d in re.findall(r"^graft (\S+)$", text, re.M)]
    included = {w for line in re.findall(r"^include (.+)$", text, re.M) for w in line.split()}
    missing = []
    for path in REPO.rglob("SConscript"):
        relative = path.relative_to(REPO)
        if SKIP & set(relative.parts) or any(p.startswith(".") for p in relative.parts):
            continue
        if str(relative) not in included and not any(relative.is_relative_to(g)
                                                     for g in grafted):
            missing.append(str(relative))
    assert not missing, f"MANIFEST.in leaves out {missing}"
