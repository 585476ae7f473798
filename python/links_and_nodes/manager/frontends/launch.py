"""Start an ln_manager as a child process and wait until it accepts clients.

For scripts, tests and benchmarks that need a private manager: its log goes to a file (a
pipe nobody drains would stall it once full), and `segments()` lists what an instance has
in /dev/shm, to check that nothing outlives it.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path


def segments(instance: str) -> list[str]:
    """Names in /dev/shm of the shared-memory segments of `instance`."""
    return sorted(n for n in os.listdir("/dev/shm") if n.startswith(f"ln.{instance}."))


@dataclass
class ManagerProcess:
    instance: str
    address: str  # HOST:PORT, for LN_MANAGER or ln.client(name, address)
    proc: subprocess.Popen[bytes]
    log: Path
    env: dict[str, str]  # the environment it runs in, plus LN_MANAGER for its clients

    def stop(self, timeout: float = 30.0) -> int:
        """SIGTERM, then SIGKILL if it does not exit within `timeout`; its exit status."""
        if self.proc.poll() is None:
            self.proc.terminate()
        try:
            return self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            return self.proc.wait()


def start_manager(instance: str, runtime_dir: Path, log: Path, *extra_args: str,
                  timeout: float = 60.0) -> ManagerProcess:
    """Run `python -m links_and_nodes.manager --port 0 --instance INSTANCE` with
    LN_RUNTIME_DIR=runtime_dir and its output in `log`; return once it listens."""
    runtime_dir.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "LN_RUNTIME_DIR": str(runtime_dir)}
    with open(log, "wb") as out:
        proc = subprocess.Popen(
            [sys.executable, "-m", "links_and_nodes.manager", "--port", "0", "--instance",
             instance, *extra_args], stdout=out, stderr=subprocess.STDOUT, env=env)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and proc.poll() is None:
        for line in log.read_text(errors="replace").splitlines():
            if " listening on " in line:
                address = line.rsplit(" ", 1)[1].strip()
                return ManagerProcess(instance, address, proc, log,
                                      {**env, "LN_MANAGER": address})
        time.sleep(0.02)
    if proc.poll() is None:
        proc.kill()
    proc.wait()
    raise RuntimeError(f"ln_manager did not start:\n{log.read_text(errors='replace')}")
