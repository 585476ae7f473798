"""Broken configurations: every file in tests/fixtures/lnc/bad starts with `# expect:` lines, and
load() must report exactly those problems, in that order (`[FILE:]LINE:COL: message`,
FILE relative to tests/fixtures/lnc/bad and only given for problems in included files).  A
`# options: strict` line after them loads the file as `--strict` does."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from links_and_nodes.manager.config import ConfigError, Problem, load

from .helpers import HEAD, cfg, write

BAD = Path(__file__).resolve().parents[2] / "fixtures" / "lnc" / "bad"
_EXPECT_RE = re.compile(r"# expect: (?:([^:\s]+):)?([0-9]+):([0-9]+): (.*)\Z")


def expected(path: Path) -> list[str]:
    lines = []
    for raw in path.read_bytes().split(b"\n"):
        m = _EXPECT_RE.match(raw.decode("utf-8", "replace"))
        if m is None:
            break
        file = BAD / m.group(1) if m.group(1) else path
        lines.append(f"{file}:{m.group(2)}:{m.group(3)}: {m.group(4)}")
    return lines


CASES = sorted(BAD.glob("*.lnc"))


def test_there_are_enough_cases() -> None:
    assert len(CASES) >= 30
    assert all(expected(p) for p in CASES), [p.name for p in CASES if not expected(p)]


@pytest.mark.parametrize("path", CASES, ids=[p.stem for p in CASES])
def test_bad_file(path: Path) -> None:
    strict = b"\n# options: strict\n" in path.read_bytes()
    with pytest.raises(ConfigError) as err:
        load(path, env={}, strict=strict)
    assert str(err.value).split("\n") == expected(path)
    assert all(isinstance(p, Problem) for p in err.value.problems)


def test_problems_of_all_files_in_file_order(tmp_path: Path) -> None:
    main = write(tmp_path, {
        "main.lnc": cfg("""
            include b.inc.lnc
            process p
                comand: p
            include a.inc.lnc
            """),
        "b.inc.lnc": "process b\n    command: b\n    priority: x\n",
        "a.inc.lnc": "process a\n    command: a\n    depends_on: zz\n",
    })
    with pytest.raises(ConfigError) as err:
        load(main)
    assert str(err.value).split("\n") == [
        f"{main}:6:5: unknown key 'comand' in process 'p' (did you mean 'command'?)",
        f"{tmp_path}/b.inc.lnc:3:15: 'priority' must be an integer, got 'x'",
        f"{tmp_path}/a.inc.lnc:3:17: unknown process or state 'zz' in 'depends_on' of "
        "process 'a'",
    ]
    assert [p.location.line for p in err.value.problems] == [6, 3, 3]


def test_a_missing_main_file(tmp_path: Path) -> None:
    with pytest.raises(ConfigError) as err:
        load(tmp_path / "none.lnc")
    assert str(err.value) == f"{tmp_path}/none.lnc:1:1: cannot read configuration: " \
                             "No such file or directory"


def test_an_unreadable_include(tmp_path: Path) -> None:
    main = write(tmp_path, {"main.lnc": HEAD + "include sub\n"})
    (tmp_path / "sub").mkdir()
    with pytest.raises(ConfigError) as err:
        load(main)
    assert str(err.value) == f"{main}:4:9: cannot read 'sub': Is a directory"


def test_duplicate_in_another_file_names_it(tmp_path: Path) -> None:
    main = write(tmp_path, {
        "main.lnc": HEAD + "include inc/p.lnc\nprocess p\n    command: p2\n",
        "inc/p.lnc": "process p\n    command: p\n",
    })
    with pytest.raises(ConfigError) as err:
        load(main)
    assert str(err.value) == f"{main}:5:9: duplicate process 'p' (first defined at inc/p.lnc:1)"
