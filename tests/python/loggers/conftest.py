"""Fixtures of the topic logger tests: a real `ln_manager -c` with the test's own instance,
ports, ln_daemon and key file (process_management's Lab), C publishers from tests/c/tools,
and a Python client of the manager."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator

import pytest
from buildtree import build_dir
from process_management import conftest as pm
from process_management.conftest import LIMIT, Lab

import links_and_nodes as ln

lab = pm.lab  # the same world as process management's tests

TOOLS = build_dir() / "tests" / "c" / "tools"


class LogLab:
    """A Lab whose manager runs, plus what the logger tests start."""

    def __init__(self, world: Lab) -> None:
        self.lab = world
        self.address = f"127.0.0.1:{world.manager_port}"
        self.env = {**world.env, "LN_MANAGER": self.address}
        self.procs: list[subprocess.Popen[str]] = []
        self.clients: list[ln.client] = []

    def start(self, body: str = "", *args: str) -> None:
        proc = self.lab.manager(self.lab.write(body), "--no-console", *args)
        self.lab.wait_listening(proc)

    def tool(self, name: str, *args: str) -> subprocess.Popen[str]:
        proc = subprocess.Popen([str(TOOLS / name), *args], env=self.env, text=True,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        self.procs.append(proc)
        return proc

    def run_tool(self, name: str, *args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([str(TOOLS / name), *args], env=self.env, text=True,
                              capture_output=True, timeout=LIMIT, check=False)

    def publisher(self, topic: str, period_us: int = 1000) -> subprocess.Popen[str]:
        """robot/joint_state on `topic` with cycle 1, 2, ... every period_us."""
        proc = self.tool("topic_tool", "pub-loop", topic, str(period_us))
        assert proc.stdout is not None
        assert proc.stdout.readline().strip() == "ready", proc.stderr.read() if \
            proc.stderr else ""
        return proc

    def client(self, name: str = "logtest") -> ln.client:
        clnt = ln.client(name, self.address, timeout=LIMIT)
        self.clients.append(clnt)
        return clnt

    def cli(self, *args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, "-m", "links_and_nodes.manager", *args,
                               ], env=self.env, text=True, capture_output=True,
                              timeout=LIMIT, check=False)


@pytest.fixture
def loglab(lab: Lab) -> Iterator[LogLab]:  # noqa: F811 - the fixture above
    ll = LogLab(lab)
    try:
        yield ll
    finally:
        for clnt in ll.clients:
            clnt.close()
        for proc in ll.procs:
            if proc.poll() is None:
                proc.kill()
            proc.communicate()

