"""Keyboard control of ln_play on a terminal: the terminal in cbreak mode (no echo, one key
at a time; Ctrl-C still interrupts) restored on every exit, a reader thread that turns keys
into commands, and the status line on stderr."""

from __future__ import annotations

import contextlib
import os
import queue
import select
import sys
import termios
import threading
import tty
from collections.abc import Iterator
from typing import Any

SEEK_STEP_NS = 5_000_000_000
KEYS = {b" ": ("toggle",), b"s": ("step",), b".": ("step",), b"\x1b[C": ("seek_by", SEEK_STEP_NS),
        b"\x1b[D": ("seek_by", -SEEK_STEP_NS), b"+": ("rate_by", 2.0), b"-": ("rate_by", 0.5),
        b"q": ("quit",)}
HELP = "keys: space pause/resume, s step, left/right -/+5 s, + / - rate x2 / /2, q quit"


def usable(fd: int) -> bool:
    """Whether keys can be read from `fd`: a terminal, and not one whose foreground job is
    another (changing its mode from the background would stop ln_play with SIGTTOU)."""
    if not os.isatty(fd):
        return False
    try:
        return os.tcgetpgrp(fd) == os.getpgrp()
    except OSError:  # not our controlling terminal: no job control to fear
        return True


@contextlib.contextmanager
def cbreak(fd: int) -> Iterator[None]:
    """The terminal of `fd` in cbreak mode, its settings restored however the block ends
    (exceptions, and signals that Python turns into them)."""
    saved = termios.tcgetattr(fd)
    try:
        tty.setcbreak(fd)
        yield
    finally:
        termios.tcsetattr(fd, termios.TCSADRAIN, saved)


def parse(data: bytes) -> tuple[list[tuple[Any, ...]], bytes]:
    """Commands of the keys in `data`, and the bytes of an unfinished escape sequence."""
    out = []
    while data:
        if data.startswith(b"\x1b["):
            if len(data) < 3:
                return out, data  # the rest may still come
            key, data = data[:3], data[3:]
        elif data == b"\x1b":
            return out, data
        else:
            key, data = data[:1], data[1:]
        if key in KEYS:
            out.append(KEYS[key])
    return out, b""


class KeyReader:
    """A thread that reads keys from `fd` into `commands` until stop()."""

    def __init__(self, fd: int) -> None:
        self.fd = fd
        self.commands: queue.Queue[tuple[Any, ...]] = queue.Queue()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="ln_play keys", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=1.0)

    def _run(self) -> None:
        pending = b""
        while not self._stop.is_set():
            ready, _, _ = select.select([self.fd], [], [], 0.1)
            if not ready:
                continue
            data = os.read(self.fd, 64)
            if not data:
                return
            cmds, pending = parse(pending + data)
            for cmd in cmds:
                self.commands.put(cmd)


def status_line(st: Any) -> None:
    """The one status line (overwritten in place) on stderr."""
    pos = (st.position_ns - st.first_ns) / 1e9
    span = (st.last_ns - st.first_ns) / 1e9
    sys.stderr.write(f"\r\x1b[K[{st.state}] {pos:9.3f} / {span:.3f} s  rate {st.rate:g}  "
                     f"{st.played} samples")
    sys.stderr.flush()
