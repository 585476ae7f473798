"""ln_play's keyboard control on a terminal (a pseudo-terminal here): step, pause/resume and
quit publish exactly the expected samples, and the terminal's settings come back on every
exit, also on SIGTERM."""

from __future__ import annotations

import os
import signal
import subprocess
import termios
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest
from polling import wait_for

from .conftest import Lab
from .player_control import Played, start_player, subscribe, write_recording
from .recording import WAIT


class Terminal:
    """A pty whose slave side is ln_play's stdin, and ln_play's stderr collected."""

    def __init__(self) -> None:
        self.master, self.slave = os.openpty()
        self.settings = termios.tcgetattr(self.slave)
        self.err = b""

    def collect(self, proc: subprocess.Popen[bytes]) -> None:
        def run() -> None:
            assert proc.stderr is not None
            for chunk in iter(lambda: proc.stderr.read1(4096), b""):  # type: ignore[union-attr]
                self.err += chunk

        threading.Thread(target=run, daemon=True).start()

    def text(self) -> str:
        return self.err.decode(errors="replace")

    def cbreak(self) -> bool:
        return not termios.tcgetattr(self.slave)[3] & (termios.ICANON | termios.ECHO)

    def close(self) -> None:
        os.close(self.master)
        os.close(self.slave)


@pytest.fixture
def term() -> Iterator[Terminal]:
    t = Terminal()
    yield t
    t.close()


def start(lab: Lab, term: Terminal, path: Path) -> subprocess.Popen[bytes]:
    proc, _ = start_player(lab, path, "--start-paused", "--wait-for-subscribers",
                           stdin=term.slave, stderr=subprocess.PIPE)
    term.collect(proc)
    wait_for(lambda: "keys:" in term.text(), "ln_play's key help")
    wait_for(term.cbreak, "the terminal in cbreak mode")
    return proc


def test_keys_step_resume_pause_quit_and_restore_the_terminal(lab: Lab, term: Terminal) -> None:
    path = lab.tmp / "keys.mcap"
    order = write_recording(path, 400, 10_000_000)
    seq = [(topic, i) for _, topic, i in order]
    with lab.client("sink") as clnt:
        played = Played(subscribe(clnt))
        proc = start(lab, term, path)
        os.write(term.master, b"s")
        assert played.take(1) == seq[:1]
        os.write(term.master, b".")
        assert played.take(1) == seq[1:2]
        assert played.nothing_more()
        os.write(term.master, b" ")  # resume
        middle = played.take(3)
        os.write(term.master, b" ")  # pause again
        wait_for(lambda: "[paused]" in term.text().rsplit("\r", 1)[-1], "the paused status line")
        os.write(term.master, b"q")
        assert proc.wait(timeout=WAIT) == 0
        wait_for(lambda: "quit after" in term.text(), "the last line")
        n = int(term.text().split("quit after ")[1].split()[0])
        assert 5 <= n < len(seq)
        rest = played.take(n - 5)
        assert seq[:2] + middle + rest == seq[:n]
        assert played.nothing_more()
    assert termios.tcgetattr(term.slave) == term.settings
    assert "Traceback" not in term.text()


def test_sigterm_restores_the_terminal(lab: Lab, term: Terminal) -> None:
    path = lab.tmp / "keys.mcap"
    write_recording(path, 10, 10_000_000)
    proc = start(lab, term, path)
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(timeout=WAIT) == 0
    assert termios.tcgetattr(term.slave) == term.settings
    wait_for(lambda: "interrupted after 0 samples" in term.text(), "the last line")
    assert "Traceback" not in term.text()
