"""Support code of the ln_manager tests: running the manager as a subprocess and waiting for
its ready line and log lines, looking at the segments of an instance in /dev/shm."""

from __future__ import annotations

import os
import re
import selectors
import signal
import subprocess
import sys
import uuid
from pathlib import Path

import pytest
from lnwire import WELCOME, WireClient
from polling import wait_for  # noqa: F401  (the manager tests import it from here)

REPO = Path(__file__).resolve().parents[3]
SHM = Path("/dev/shm")
WAIT = 60.0  # seconds; only ever an upper bound while waiting for something to happen
READY = re.compile(r"^ln_manager: instance (.+) listening on (\S+):(\d+)$")




def segments(instance: str) -> list[str]:
    """Names (without /dev/shm/) of the instance's segments, sorted.  Characters that
    cannot be in a segment name are '_' there, as docs/manager.md says."""
    safe = re.sub(r"[^A-Za-z0-9_-]", "_", instance)
    return sorted(p.name for p in SHM.glob(f"ln.{safe}.*"))


def unique_instance() -> str:
    return f"t{os.getpid()}_{uuid.uuid4().hex[:8]}"


class Manager:
    """A running ln_manager subprocess."""

    def __init__(self, instance: str, runtime: Path, log: Path, args: list[str]) -> None:
        self.instance = instance
        self.runtime = runtime
        self.log_path = log
        path = [str(REPO / "python"), *filter(None, [os.environ.get("PYTHONPATH")])]
        env = dict(os.environ, LN_RUNTIME_DIR=str(runtime), PYTHONPATH=os.pathsep.join(path))
        cmd = [sys.executable, "-m", "links_and_nodes.manager", "--port", "0",
               "--instance", instance, *args]
        with open(log, "ab") as err:
            self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=err, env=env,
                                         cwd=REPO)
        self.port = 0

    def wait_ready(self) -> Manager:
        assert self.proc.stdout is not None
        line = self._read_line()
        match = READY.match(line)
        assert match, f"unexpected first line {line!r}; log:\n{self.log()}"
        assert match.group(1) == self.instance
        self.port = int(match.group(3))
        return self

    def _read_line(self) -> str:
        assert self.proc.stdout is not None
        with selectors.DefaultSelector() as sel:
            sel.register(self.proc.stdout, selectors.EVENT_READ)
            if not sel.select(WAIT):
                pytest.fail(f"ln_manager printed nothing; log:\n{self.log()}")
        return self.proc.stdout.readline().decode().rstrip("\n")

    def log(self) -> str:
        return self.log_path.read_text(errors="replace")

    def wait_log(self, pattern: str) -> re.Match[str]:
        """Wait until a log line matches the regex `pattern`; the match."""
        regex = re.compile(pattern, re.M)
        match = wait_for(lambda: regex.search(self.log()), f"log line /{pattern}/")
        assert isinstance(match, re.Match)
        return match

    def client(self, name: str | None = None) -> WireClient:
        """A connected client; after HELLO if `name` is given."""
        client = WireClient(self.port)
        if name is not None:
            reply = client.hello(name)
            assert reply.type == WELCOME, reply
        return client

    def stop(self, signum: int = signal.SIGTERM) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(signum)
        return self.proc.wait(WAIT)

    def kill(self) -> None:
        self.proc.kill()
        self.proc.wait(WAIT)


def require_manager_library() -> None:
    """Skip a module that runs the manager when libln (with the ring administration the
    manager needs) is not built; under CI that is a failure, not a skip."""
    try:
        import links_and_nodes.manager.registry.segments  # noqa: F401
    except (ImportError, AttributeError) as exc:
        if os.environ.get("CI"):
            raise
        pytest.skip(f"libln with ring administration is not built: {exc}",
                    allow_module_level=True)
