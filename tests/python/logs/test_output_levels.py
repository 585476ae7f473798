"""Levels from process output (docs/logging.md, "Levels from process output"): a process's
`log_level_regex` makes the output lines it matches log lines of the manager, with the level
of its `level` group and the text of its `text` group; lines it does not match stay output
only.  A regex without a `level` group is refused where it is written."""

from __future__ import annotations

import pytest
from process_management.conftest import Lab, lab, wait_for  # noqa: F401 - fixture

from links_and_nodes.manager.config import ConfigError, parse_text
from links_and_nodes.manager.processes.output_levels import output_level

REGEX = r"^\[(?P<level>[A-Za-z]+)\] (?P<text>.*)"


def test_output_lines_become_log_lines(lab: Lab) -> None:  # noqa: F811
    script = ("echo '[WARN] disk low'; echo 'plain line'; echo '[error] arm fault'; "
              "echo '[SHOUT] odd word'; echo ready; exec sleep 600")
    config = lab.write(f"process talker\ncommand: /bin/sh -c \"{script}\" {lab.instance}\n"
                       f"log_level_regex: {REGEX}\nready_regex: ^ready\n\n")
    proc = lab.manager(config, "--no-console", "--start-all")
    lab.wait_listening(proc)
    with lab.connect() as mgr:
        mgr.wait_ready("talker", 60)
        wait_for(lambda: len(mgr.log(process="talker")) == 3, "three log lines")
        got = mgr.log(process="talker")
        assert [(e["level"], e["text"]) for e in got] == [
            (30, "disk low"), (40, "arm fault"), (20, "odd word")]
        assert all(e["source"] == "output" and e["process"] == "talker"
                   and e["host"] == "localhost" and e["file"] == "pty" for e in got)  # the stream
        assert [e["text"] for e in mgr.log(level="error")] == ["arm fault"]
        assert "plain line" in mgr.output("talker")


def test_regex_without_a_level_group_is_refused_where_written() -> None:
    text = ("instance\nname: demo\nmanager: :54414\n"
            "process p\ncommand: p\nlog_level_regex: ^(\\w+): (.*)\n")
    with pytest.raises(ConfigError) as err:
        parse_text(text, "/nowhere/x.lnc")
    assert "/nowhere/x.lnc:6:18:" in str(err.value)
    assert "needs a group named level" in str(err.value)


@pytest.mark.parametrize(("line", "expected"), [
    ("[WARN] x", (30, "x")), ("[fatal] y", (50, "y")), ("[DEBUG] z", (10, "z")),
    ("[Info] w", (20, "w")), ("no level here", None),
])
def test_output_level(line: str, expected: tuple[int, str] | None) -> None:
    assert output_level(REGEX, line) == expected
