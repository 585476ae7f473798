"""The real-world mds written for the original Links and Nodes (../shared/real_ln/md) generate
C, C++ and Python that compile and import; the few that are really invalid fail with the
exact `file:line:col: message` listed here. Skipped without the corpus only outside CI.

Each md dir (SET) of the corpus is one test. The generator runs in process once per md and
language: a SET cannot go into one output file, since some SETs hold the same md under an
old and a new name (`robotkernel_module_list` beside `robotkernel/module_list`), which give
the same C type name. Each compiler then runs once per SET over all its headers.
"""

from __future__ import annotations

import contextlib
import ctypes
import io
import os
import subprocess
from pathlib import Path

import pytest
from gen_modules import load_module

from ln_generate.cli import main

REPO = Path(__file__).resolve().parents[3]
CORPUS = REPO.parent / "shared" / "real_ln" / "md"
CORPUS_SIZE = 139

if not CORPUS.is_dir():
    if os.environ.get("CI"):
        pytest.fail(f"the real-world md corpus {CORPUS} is missing (CI=1: this is a failure)",
                    pytrace=False)
    pytest.skip(f"the real-world md corpus {CORPUS} is not here", allow_module_level=True)

_LEN_CLASH = ("an explicit 'uint32_t data_len' beside 'uint8_t* data': the dynamic field "
              "already has that length member, so the struct would have it twice")
#: "SET/md name" -> (why it is invalid, the error after `file:`) for every md that must fail.
EXPECTED_FAILURES: dict[str, tuple[str, str]] = {
    "service_provider_memory_inspection__share/robotkernel/memory_inspection/write": (
        _LEN_CLASH,
        "6:10: implicit length field 'data_len' of 'data' clashes with field 'data_len' "
        "(first defined at line 5)",
    ),
    "service_provider_memory_inspection__share_ln/robotkernel/memory_inspection/write": (
        _LEN_CLASH,
        "6:10: implicit length field 'data_len' of 'data' clashes with field 'data_len' "
        "(first defined at line 5)",
    ),
}
_MERGED = "8:1: warning: section 'response' appears again (first at line 5); its fields are " \
          "appended to it"
#: "SET/md name" -> the warning after `file:` of every md that generates with a warning.
EXPECTED_WARNINGS: dict[str, str] = {
    "robotkernel__share_ln/robotkernel/remove_module": _MERGED,
    "robotkernel__share_ln/robotkernel_remove_module": _MERGED,
    "robotkernel__src/robotkernel/remove_module": _MERGED,
}
LANGS = {"c": ".h", "cpp": ".hpp", "python": ".py"}
COMPILERS = {
    ".h": ["gcc", "-std=c11", "-Wall", "-Wextra", "-Werror", "-pedantic", "-x", "c"],
    ".hpp": ["g++", "-std=c++17", "-Wall", "-Wextra", "-Werror", "-pedantic", "-x", "c++"],
}


def md_sets() -> list[Path]:
    return sorted(p for p in CORPUS.iterdir() if p.is_dir())


def md_names(root: Path) -> list[str]:
    return sorted(p.relative_to(root).as_posix() for p in root.rglob("*") if p.is_file())


def generate(root: Path, name: str, out: Path) -> tuple[int, str]:
    """Run the CLI in process; (exit status, stderr)."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        rc = main(["--md-dir", str(root), "-o", str(out), name])
    return rc, err.getvalue()


def test_corpus_is_complete() -> None:
    names = [f"{s.name}/{n}" for s in md_sets() for n in md_names(s)]
    assert len(names) == CORPUS_SIZE
    assert set(EXPECTED_FAILURES) <= set(names) and set(EXPECTED_WARNINGS) <= set(names)


@pytest.mark.parametrize("md_set", md_sets(), ids=lambda p: p.name)
def test_md_set(md_set: Path, tmp_path: Path) -> None:
    outputs: dict[str, list[Path]] = {suffix: [] for suffix in LANGS.values()}
    for i, name in enumerate(md_names(md_set)):
        key = f"{md_set.name}/{name}"
        path = md_set / name
        for lang, suffix in LANGS.items():
            out = tmp_path / f"md{i}{suffix}"
            rc, err = generate(md_set, name, out)
            if key in EXPECTED_FAILURES:
                assert (rc, err) == (1, f"{path}:{EXPECTED_FAILURES[key][1]}\n"), (key, lang)
                assert not out.exists()
                continue
            warning = f"{path}:{EXPECTED_WARNINGS[key]}\n" if key in EXPECTED_WARNINGS else ""
            assert (rc, err) == (0, warning), (key, lang)
            outputs[suffix].append(out)
    for suffix, cmd in COMPILERS.items():
        if outputs[suffix]:
            cc = subprocess.run([*cmd, "-fsyntax-only", *map(str, outputs[suffix])],
                                capture_output=True, text=True)
            assert cc.returncode == 0, cc.stderr
    for out in outputs[".py"]:
        module = load_module(f"real_ln_{md_set.name}_{out.stem}", out)
        for cls in module.MESSAGES.values():
            parts = [cls] if not hasattr(cls, "KIND") else [t for _, t in cls._fields_]
            for part in parts:
                assert ctypes.sizeof(part) == (part.SIZE or 1), part.__name__
            cls().to_dict()
