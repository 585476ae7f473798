"""`ln_manager check` as a lab's CI runs it: a separate process, exit status 0/1/2,
warnings and errors on stderr as `file:line:col:`, `--print` as a table, `--json`,
`--strict`, `-D`; and the table of the original's keywords (keywords.txt) against what
the reader does and what docs/configuration.md says."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from links_and_nodes.manager.config import ConfigError, parse_text
from links_and_nodes.manager.config.keywords import (
    IMPLEMENTED,
    NO_EFFECT,
    REFUSED,
    keyword_status,
)

from .helpers import cfg, write

REPO = Path(__file__).resolve().parents[3]
KEYWORDS = REPO.parent / "shared" / "real_ln" / "keywords.txt"


def ln_check(*argv: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "links_and_nodes.manager", "check", *argv],
                          capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)


GOOD = cfg("""
    defines
    base: %(ifndef "base", "/opt/robot")
    process sensor
    command: %(base)/bin/sensor --rate 1000
    add_message_definition_dir: %(CURDIR)/no_mds
    process controller
    command: %(base)/bin/controller
    depends_on: sensor
    """)


def test_check_prints_warnings_and_a_table(tmp_path: Path) -> None:
    main = write(tmp_path, {"robot.lnc": GOOD})
    r = ln_check(str(main), "--print", "-D", "base=/srv/r")
    assert r.returncode == 0, r.stderr
    assert r.stderr.splitlines() == [
        f"{main}:8:29: warning: message definition directory '{tmp_path}/no_mds' not found "
        "(ignored)",
        f"ln_manager check: {main}: ok (2 processes, 1 warning)"]
    assert r.stdout.splitlines() == [
        "NAME        NODE       DEPENDS ON  COMMAND",
        "sensor      localhost  -           /srv/r/bin/sensor --rate 1000",
        "controller  localhost  sensor      /srv/r/bin/controller"]


def test_check_json_and_strict(tmp_path: Path) -> None:
    main = write(tmp_path, {"robot.lnc": GOOD})
    r = ln_check(str(main), "--json", "--print")
    assert r.returncode == 0
    result = json.loads(r.stdout)
    assert result["ok"] is True and result["errors"] == []
    assert [w["line"] for w in result["warnings"]] == [8]
    assert [(p["name"], p["depends_on"]) for p in result["processes"]] == [
        ("sensor", []), ("controller", ["sensor"])]
    r = ln_check(str(main), "--strict")
    assert r.returncode == 1
    assert r.stderr.splitlines()[0] == (
        f"{main}:8:29: message definition directory '{tmp_path}/no_mds' not found (ignored) "
        "[warning, an error with --strict]")


def test_check_errors_exit_1_and_bad_usage_exit_2(tmp_path: Path) -> None:
    main = write(tmp_path, {"bad.lnc": cfg("process p\ncomand: x\n")})
    r = ln_check(str(main))
    assert r.returncode == 1
    assert r.stderr.splitlines() == [
        f"{main}:5:1: unknown key 'comand' in process 'p' (did you mean 'command'?)",
        f"ln_manager check: {main}: 1 error"]
    assert ln_check(str(main), "-D", "novalue").returncode == 2
    assert ln_check().returncode == 2
    missing = ln_check(str(tmp_path / "nothing.lnc"))
    assert missing.returncode == 1 and "cannot read configuration" in missing.stderr


def test_ln_manager_c_prints_warnings(tmp_path: Path) -> None:
    """The manager itself reports the warnings when it loads a file (and refuses it with
    --strict before starting anything)."""
    main = write(tmp_path, {"robot.lnc": GOOD})
    r = subprocess.run([sys.executable, "-m", "links_and_nodes.manager", "-c", str(main),
                        "--strict", "--no-console"], capture_output=True, text=True,
                       timeout=60, stdin=subprocess.DEVNULL)
    assert r.returncode == 2
    assert "[warning, an error with --strict]" in r.stderr
    assert "configuration has errors, nothing started" in r.stderr


# ---------------------------------------------------------------- the original's keywords

def keywords() -> list[tuple[str, str]]:
    if not KEYWORDS.is_file():
        if os.environ.get("CI"):
            pytest.fail(f"{KEYWORDS} is missing (CI=1: this is a failure)")
        pytest.skip(f"{KEYWORDS} is not here")
    out = []
    for line in KEYWORDS.read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            word, category, _ = line.split("\t")
            out.append((word, category))
    return out


def docs_table() -> dict[str, str]:
    """keyword -> status of the table in docs/configuration.md."""
    rows = {}
    for line in (REPO / "docs" / "configuration.md").read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.startswith("| `") and len(cells) >= 3:
            rows[cells[0].strip("`")] = cells[2]
    return rows


def test_every_original_keyword_has_a_status_and_the_docs_agree() -> None:
    table = docs_table()
    for word, category in keywords():
        status, _ = keyword_status(word, category)
        assert status in (IMPLEMENTED, NO_EFFECT, REFUSED)
        assert table.get(word) == status, (word, category, status)


def test_refused_keywords_say_so_with_an_alternative() -> None:
    refused = [w for w, c in keywords() if keyword_status(w, c)[0] == REFUSED]
    assert refused  # the original had keys this reader does not do
    for word in refused:  # verbose2_base was an instance key, the others process keys
        body = f"{word}: x\n" if word == "verbose2_base" else f"process p\ncommand: p\n{word}: x\n"
        text = "instance\nname: t\nmanager: :1\n" + body
        with pytest.raises(ConfigError) as err:
            parse_text(text, "/tmp/k.lnc", env={})
        message = err.value.problems[0].message
        assert "not supported by links_and_nodes (" in message, message
        assert keyword_status(word, "key")[1] in message


def test_flags_without_effect_are_accepted() -> None:
    flags = [w for w, c in keywords() if c == "flag"]
    text = "instance\nname: t\nmanager: :1\nprocess p\ncommand: p\nflags: " + ", ".join(flags)
    config = parse_text(text, "/tmp/k.lnc", env={})
    assert config.processes["p"].flags == set(flags)
