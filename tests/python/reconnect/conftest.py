"""Fixtures of the manager restart tests: a `Restarts` world per test (unique instance, own
runtime directory, a manager port that every successor takes over), the C tools of the topic
and service tests started against it, and a check that no segment or process of the test
outlives it."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import uuid
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

REPO = Path(__file__).resolve().parents[3]
# the manager tests' wire client, for the tests that send frames by hand
sys.path.insert(0, str(REPO / "tests" / "python" / "manager"))

from polling import wait_for  # noqa: E402
from topics.conftest import TOOLS, wait_ready  # noqa: E402

import links_and_nodes as ln  # noqa: E402
from links_and_nodes.manager.frontends import launch  # noqa: E402
from links_and_nodes.manager.frontends.launch import ManagerProcess, segments  # noqa: E402
from links_and_nodes.tools import scripting  # noqa: E402

LIMIT = 60.0  # seconds: an upper bound against hangs, never a pass criterion

ln.add_message_definition_dir(REPO / "tests" / "fixtures" / "md" / "topics")
ln.add_message_definition_dir(REPO / "tests" / "fixtures" / "md" / "services")


@dataclass
class Restarts:
    """One test's instance and the managers that serve it one after the other."""

    tmp: Path
    instance: str
    window: float = 5.0  # --adopt-window of the managers started by restart()
    managers: list[ManagerProcess] = field(default_factory=list)
    tools: list[subprocess.Popen[str]] = field(default_factory=list)
    clients: list[ln.client] = field(default_factory=list)

    @property
    def manager(self) -> ManagerProcess:
        return self.managers[-1]

    @property
    def address(self) -> str:
        return self.managers[0].address

    @property
    def port(self) -> str:
        return self.address.rsplit(":", 1)[1]

    @property
    def env(self) -> dict[str, str]:
        return self.managers[0].env

    def start(self, *args: str) -> ManagerProcess:
        """A manager on the instance's port (the first one picks it)."""
        port = ["--port", self.port] if self.managers else []
        window = ["--adopt-window", f"{self.window:g}"]
        log = self.tmp / f"manager-{len(self.managers)}.log"
        mgr = launch.start_manager(self.instance, self.tmp / "run", log, *port, *window,
                                   *args)
        self.managers.append(mgr)
        return mgr

    def kill(self) -> None:
        """SIGKILL the running manager: nothing of it is cleaned up."""
        self.manager.proc.send_signal(signal.SIGKILL)
        self.manager.proc.wait()

    def restart(self, *args: str) -> ManagerProcess:
        self.kill()
        return self.start(*args)

    def log(self, index: int = -1) -> str:
        return self.managers[index].log.read_text(errors="replace")

    def wait_log(self, text: str, index: int = -1) -> None:
        wait_for(lambda: text in self.log(index), f"log line {text!r}")

    def control(self) -> scripting.Manager:
        return scripting.connect(self.address, timeout=LIMIT)

    def topics(self) -> dict[str, dict[str, object]]:
        with self.control() as mgr:
            return {t["name"]: t for t in mgr.topics()}

    def services(self) -> dict[str, dict[str, object]]:
        with self.control() as mgr:
            return {s["name"]: s for s in mgr.services()}

    def client(self, name: str, **kwargs: object) -> ln.client:
        clnt = ln.client(name, self.address, **kwargs)  # type: ignore[arg-type]
        self.clients.append(clnt)
        return clnt

    def tool(self, exe: str, *args: str) -> subprocess.Popen[str]:
        """A C tool (topic_tool, service_tool), once it said "ready"."""
        path = TOOLS / exe
        if not path.exists():
            pytest.fail(f"{path} is missing: run scons first")
        proc = subprocess.Popen([str(path), *args], stdout=subprocess.PIPE, text=True,
                                env={**self.env, "LN_MANAGER": self.address})
        self.tools.append(proc)
        wait_ready(proc, LIMIT)
        return proc

    def python(self, script: str, *args: str) -> subprocess.Popen[str]:
        """A Python client process running `script` (stdin/stdout pipes)."""
        env = {**self.env, "LN_MANAGER": self.address,
               "PYTHONPATH": os.pathsep.join([str(REPO / "python"), str(REPO)])}
        proc = subprocess.Popen([sys.executable, "-c", script, *args], stdin=subprocess.PIPE,
                                stdout=subprocess.PIPE, text=True, env=env)
        self.tools.append(proc)
        return proc


@pytest.fixture
def restarts(tmp_path: Path) -> Iterator[Restarts]:
    world = Restarts(tmp_path, f"rc{os.getpid()}x{uuid.uuid4().hex[:8]}")
    world.start()
    try:
        yield world
    finally:
        for clnt in world.clients:
            clnt.close()
        for tool in world.tools:
            if tool.poll() is None:
                tool.kill()
            tool.wait()
            for pipe in (tool.stdin, tool.stdout):
                if pipe is not None:
                    pipe.close()
        status = world.manager.stop()
        for mgr in world.managers[:-1]:
            if mgr.proc.poll() is None:
                mgr.proc.kill()
                mgr.proc.wait()
    assert status in (0, -9), f"the last manager exited with {status}"
    assert segments(world.instance) == [], "segments outlived every client and manager"


def read_until(port: Any, match: Any, what: str) -> tuple[Any, list[int]]:
    """Read `port` until `match(packet)`; the packet and the sequence numbers read."""
    seqs: list[int] = []

    def found() -> object:
        while (pkt := port.read(timeout=0.05)) is not None:  # all there is, then a pause
            seqs.append(port.info.seq)
            if match(pkt):
                return pkt
        return None

    return wait_for(found, what, LIMIT), seqs
