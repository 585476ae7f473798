"""A process's `command` is split into its argv when the configuration is loaded
(config/argv.py): a bad quote is a configuration error at its file:line:col, for
`ln_manager check` and `ln_manager -c` alike, not a failure when the process starts."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from links_and_nodes.manager.config.argv import CommandSplitError, split_command

from .helpers import cfg, load_files, write

BAD = cfg("""
    process a
    command: /bin/echo it's here
""")


@pytest.mark.parametrize("command, argv", [
    ("a b  c", ["a", "b", "c"]), ("echo 'x y' \"z w\"", ["echo", "x y", "z w"]),
    (r"echo a\ b", ["echo", "a b"]), ("echo \"it's\"", ["echo", "it's"]),
])
def test_split(command: str, argv: list[str]) -> None:
    assert split_command(command) == argv


@pytest.mark.parametrize("command, offset, what", [
    ("echo 'x y", 5, "unbalanced single quote"), ('echo a "b c', 7, "unbalanced double quote"),
    ("echo x \\", 7, "backslash that escapes nothing"), ("a 'b' \"c' d", 6, "double quote"),
])
def test_split_errors_say_where(command: str, offset: int, what: str) -> None:
    with pytest.raises(CommandSplitError) as info:
        split_command(command)
    assert info.value.offset == offset
    assert what in str(info.value)


def test_the_loaded_process_has_its_argv(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        process a
        command: /bin/echo 'one two' three
        process b
        command: echo $HOME 'unclosed
        flags: start_in_shell
    """)})
    assert config.processes["a"].argv == ["/bin/echo", "one two", "three"]
    assert config.processes["b"].argv == []  # the shell splits it


@pytest.mark.parametrize("argv", [["check"], ["-c"]], ids=["check", "-c"])
def test_cli_reports_the_quote_at_its_column(tmp_path: Path, argv: list[str]) -> None:
    path = write(tmp_path, {"main.lnc": BAD})
    result = subprocess.run([sys.executable, "-m", "links_and_nodes.manager", *argv, str(path),
                             "--port", "0"] if argv == ["-c"] else
                            [sys.executable, "-m", "links_and_nodes.manager", *argv, str(path)],
                            capture_output=True, text=True, timeout=60,
                            stdin=subprocess.DEVNULL)
    assert result.returncode != 0
    assert (f"{path}:5:22: process 'a': unbalanced single quote in the command: it is never "
            "closed") in result.stderr.splitlines()
