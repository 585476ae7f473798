"""The ctypes mirrors of libln_pull's structs (struct ln_pull_sub in links_and_nodes.
_pull_lib, the codec's in ndn_ctypes.py) against the C headers: size and every field's
offset, printed by a tiny C program compiled here."""

from __future__ import annotations

import ctypes
import shutil
import subprocess
from pathlib import Path

import pytest
from buildtree import REPO

from links_and_nodes import _pull_lib as P

from .ndn_ctypes import STRUCTS

MIRRORS = {"ln_pull_sub": P.Sub, "ln_pull_options": P.Options, "ln_pull_stats": P.Stats,
           "ln_pull_slot": P.Slot, **STRUCTS}


def test_mirrors_match_the_headers(tmp_path: Path) -> None:
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    lines = []
    for cname, mirror in MIRRORS.items():
        lines.append(f'    printf("{cname} %zu\\n", sizeof({cname}));')
        lines += [f'    printf("{cname}.{f} %zu\\n", offsetof({cname}, {f}));'
                  for f, *_ in mirror._fields_]
    source = tmp_path / "sizes.c"
    source.write_text('#include <stddef.h>\n#include <stdio.h>\n#include "ln/pull.h"\n'
                      'int main(void) {\n' + "\n".join(lines) + "\n    return 0;\n}\n")
    exe = tmp_path / "sizes"
    subprocess.run([cc, "-std=c99", "-I", str(REPO / "libln_pull" / "include"), str(source),
                    "-o", str(exe)], check=True, capture_output=True, text=True)
    printed = dict(line.split() for line in subprocess.run(
        [str(exe)], check=True, capture_output=True, text=True).stdout.splitlines())
    for cname, mirror in MIRRORS.items():
        assert int(printed[cname]) == ctypes.sizeof(mirror), cname
        for f, *_ in mirror._fields_:
            assert int(printed[f"{cname}.{f}"]) == getattr(mirror, f).offset, f"{cname}.{f}"
    size_of = getattr(P.lib, "ln_pull_sub_size", None)
    if size_of is not None:
        size_of.restype = ctypes.c_size_t
        assert size_of() == ctypes.sizeof(P.Sub)
