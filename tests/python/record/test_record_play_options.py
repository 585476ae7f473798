"""ln_play's control options: `--clock` with or without HZ before the files, the control
service's name, and the key parser of the terminal control."""

from __future__ import annotations

import pytest

from links_and_nodes.record import keyboard, play_cli
from links_and_nodes.record.control_service import default_name


@pytest.mark.parametrize(("argv", "hz"), [
    (["--clock", "a.mcap"], 100.0),
    (["--clock", "50", "a.mcap"], 50.0),
    (["--clock=20", "a.mcap"], 20.0),
    (["a.mcap", "--clock"], 100.0),
    (["a.mcap"], None),
])
def test_clock_option(argv: list[str], hz: float | None) -> None:
    args = play_cli.parser().parse_args(play_cli._clock_without_hz(argv))
    assert (args.clock, args.files) == (hz, ["a.mcap"])


def test_control_service_name() -> None:
    args = play_cli.parser().parse_args(["--control-service", "x.ctl", "a.mcap"])
    assert args.control_service == "x.ctl"
    assert default_name("ln_play-2") == "ln_play-2.control"


def test_keys() -> None:
    cmds, rest = keyboard.parse(b" s.+-q\x1b[C\x1b[Dx\x1b[")
    assert cmds == [("toggle",), ("step",), ("step",), ("rate_by", 2.0), ("rate_by", 0.5),
                    ("quit",), ("seek_by", 5_000_000_000), ("seek_by", -5_000_000_000)]
    assert rest == b"\x1b["  # an arrow key not complete yet
    assert keyboard.parse(rest + b"C") == ([("seek_by", 5_000_000_000)], b"")
    assert keyboard.parse(b"\x1b") == ([], b"\x1b")
    assert keyboard.parse(b"\x1bs") == ([("step",)], b"")  # a lone Escape is ignored
