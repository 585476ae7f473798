"""A real `ln_manager -c FILE` driven through its console (stdin/stdout), for the tests of
console commands: `console_manager(...)` starts it, waits for "listening on", reads its
output in a thread, and at the end stops it with SIGTERM, kills a daemon it started and
checks its exit status and that it left no shared memory."""

from __future__ import annotations

import os
import queue
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from polling import pids_with

from links_and_nodes.manager.frontends.launch import segments


@dataclass
class Console:
    proc: subprocess.Popen[str]
    address: str
    limit: float  # seconds: the bound against hangs of expect()
    lines: queue.Queue[str | None] = field(default_factory=queue.Queue)
    seen: list[str] = field(default_factory=list)  # every line expect() has read

    def send(self, line: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()

    def expect(self, accept: Callable[[str], bool], what: str) -> list[str]:
        """Read output lines up to and including the first `accept` takes; those lines."""
        got: list[str] = []
        deadline = time.monotonic() + self.limit
        while True:
            try:
                line = self.lines.get(timeout=max(deadline - time.monotonic(), 0.01))
            except queue.Empty:
                pytest.fail(f"gave up waiting for {what}; got {got}")
            if line is None:
                pytest.fail(f"the manager ended before {what}; got {got}")
            got.append(line)
            self.seen.append(line)
            if accept(line):
                return got


@contextmanager
def console_manager(config: Path, instance: str, port: int, daemon_port: int,
                    env: dict[str, str], limit: float,
                    cwd: Path | None = None) -> Iterator[Console]:
    """The manager of `config` (instance `instance` on 127.0.0.1:`port`, its daemon on
    `daemon_port`) with `env`; its stderr goes to manager.log beside `config`."""
    log_path = config.parent / "manager.log"
    with open(log_path, "w") as log:
        proc = subprocess.Popen([sys.executable, "-m", "links_and_nodes.manager", "-c",
                                 str(config)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                stderr=log, text=True, env=env, cwd=cwd)
    assert proc.stdout is not None
    first = proc.stdout.readline()
    assert "listening on" in first, log_path.read_text()
    console = Console(proc, f"127.0.0.1:{port}", limit)

    def pump() -> None:
        assert proc.stdout is not None
        for line in proc.stdout:
            console.lines.put(line.rstrip("\n"))
        console.lines.put(None)

    threading.Thread(target=pump, daemon=True).start()
    try:
        yield console
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
        try:
            code = proc.wait(limit)
        except subprocess.TimeoutExpired:
            proc.kill()
            code = proc.wait()
        for pid in pids_with(f"--port\0{daemon_port}\0"):  # a daemon it started
            os.kill(pid, signal.SIGKILL)
    assert code == 0, log_path.read_text()
    assert segments(instance) == []
