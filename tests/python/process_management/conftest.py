"""Fixtures of the end-to-end process management tests: a configuration written by the test,
run by a real `ln_manager -c` with its own instance, manager port, ln_daemon port, key file
and runtime directory; the scripting API connected to it.  At the end the manager is stopped,
the test's daemon killed and every process the test started checked gone."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import uuid
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from polling import (  # noqa: F401  (shared with the tests of this package)
    free_daemon_port,
    free_port,
    pids_with,
    wait_for,
)

from links_and_nodes.tools import scripting

LIMIT = 60.0  # upper bound for anything to happen, never a measurement
REPO = Path(__file__).resolve().parents[3]


def parent(pid: int) -> int:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return 0
    return int(stat.rsplit(")", 1)[1].split()[1])


@dataclass
class Lab:
    """One test's world: where things go and what runs."""

    tmp: Path
    instance: str
    env: dict[str, str]
    manager_port: int
    daemon_port: int
    managers: list[subprocess.Popen[str]] = field(default_factory=list)

    def write(self, body: str, name: str = "test.lnc") -> Path:
        """A configuration with this test's instance section, then `body`."""
        path = self.tmp / name
        path.write_text(f"instance\nname: {self.instance}\nmanager: 127.0.0.1:"
                        f"{self.manager_port}\n\n{body}")
        return path

    def manager(self, config: Path, *args: str, stdin: int | None = subprocess.DEVNULL
                ) -> subprocess.Popen[str]:
        log = open(self.tmp / f"manager-{len(self.managers)}.log", "w")  # noqa: SIM115
        proc = subprocess.Popen([sys.executable, "-m", "links_and_nodes.manager", "-c",
                                 str(config), *args], stdin=stdin, stdout=subprocess.PIPE,
                                stderr=log, text=True, env=self.env)
        log.close()
        self.managers.append(proc)
        return proc

    def wait_listening(self, proc: subprocess.Popen[str]) -> str:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert "listening on" in line, f"manager did not start: {line!r}\n{self.log()}"
        return line.rsplit(" ", 1)[1].strip()

    def connect(self) -> scripting.Manager:
        return scripting.connect(f"127.0.0.1:{self.manager_port}", timeout=LIMIT)

    def log(self, index: int = -1) -> str:
        logs = sorted(self.tmp.glob("manager-*.log"))
        return logs[index].read_text() if logs else ""

    def daemon_pids(self, *, all_forks: bool = False) -> list[int]:
        """The test's ln_daemon; with all_forks also its forks that have not exec'd yet
        or keep a process (they share its command line)."""
        pids = pids_with(f"--port\0{self.daemon_port}\0")
        if all_forks:
            return pids
        return [pid for pid in pids if parent(pid) not in pids]


@pytest.fixture
def lab(tmp_path: Path) -> Iterator[Lab]:
    instance = f"pm-{uuid.uuid4().hex[:10]}"
    runtime = tmp_path / "run"
    env = {**os.environ, "LN_RUNTIME_DIR": str(runtime),
           "LN_DAEMON_KEY_FILE": str(tmp_path / "keys" / "daemon.key"),
           "LN_ARBITER_PORT": str(free_daemon_port()), "PYTHONUNBUFFERED": "1"}
    lab = Lab(tmp_path, instance, env, free_port(), int(env["LN_ARBITER_PORT"]))
    try:
        yield lab
    finally:
        for proc in lab.managers:
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM)
                try:
                    proc.wait(timeout=LIMIT)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait()
            if proc.stdout is not None:
                proc.stdout.close()
        for pid in lab.daemon_pids(all_forks=True):
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        leftovers = pids_with(instance)
        for pid in leftovers:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        assert not leftovers, f"processes of the test left running: {leftovers}"

