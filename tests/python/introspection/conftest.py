"""Fixtures of the live introspection tests: a private manager per test (unique instance,
free port, own runtime directory) whose md search path holds tests/fixtures/md/introspect, the
test's publisher and provider processes, and `ln_manager topic|md|service ...` run as a
client process whose own environment does not know that directory (so the mds come from
the manager's search path).  Everything a test started is stopped after it, and no segment
of its instance is left."""

from __future__ import annotations

import os
import selectors
import subprocess
import sys
import uuid
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from links_and_nodes.manager.frontends import launch
from links_and_nodes.manager.frontends.launch import ManagerProcess, segments

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[2]
MDS = REPO / "tests" / "fixtures" / "md" / "introspect"
OTHER_MDS = REPO / "tests" / "fixtures" / "md" / "introspect_other"  # the same names, other layouts
LIMIT = 60.0  # seconds: an upper bound against hangs, never a pass criterion
PERIOD = 0.02  # seconds between the test publisher's samples


def spawn(address: str, env: dict[str, str], script: str, *args: str
          ) -> subprocess.Popen[str]:
    """Run tests/python/introspection/SCRIPT ADDRESS ARGS... and wait for its "ready"."""
    proc = subprocess.Popen([sys.executable, str(HERE / script), address, *args],
                            stdout=subprocess.PIPE, text=True, env=env)
    assert proc.stdout is not None
    with selectors.DefaultSelector() as sel:
        sel.register(proc.stdout, selectors.EVENT_READ)
        if not sel.select(LIMIT):
            proc.kill()
            pytest.fail(f"{script} did not say ready within {LIMIT} s")
    line = proc.stdout.readline()
    if line.strip() != "ready":
        proc.kill()
        pytest.fail(f"{script} did not start: {line!r}")
    return proc


def stop(procs: list[subprocess.Popen[str]]) -> None:
    for proc in procs:
        if proc.poll() is None:
            proc.kill()
        proc.wait()
        if proc.stdout is not None:
            proc.stdout.close()


@dataclass
class Lab:
    """A test's manager and the processes it started against it."""

    manager: ManagerProcess
    procs: list[subprocess.Popen[str]] = field(default_factory=list)

    @property
    def address(self) -> str:
        return self.manager.address

    def client_env(self) -> dict[str, str]:
        env = {k: v for k, v in os.environ.items() if k != "LN_MESSAGE_DEFINITION_DIRS"}
        return {**env, "LN_MANAGER": self.address, "LN_RUNTIME_DIR":
                self.manager.env["LN_RUNTIME_DIR"]}

    def spawn(self, script: str, *args: str) -> subprocess.Popen[str]:
        proc = spawn(self.address, self.client_env(), script, *args)
        self.procs.append(proc)
        return proc

    def publisher(self, topic: str = "probe.state", md_dir: Path = MDS,
                  *extra: str) -> subprocess.Popen[str]:
        return self.spawn("probe_publisher.py", topic, str(PERIOD), str(md_dir), *extra)

    def provider(self, name: str = "probe.adjust", md_dir: Path = MDS
                 ) -> subprocess.Popen[str]:
        return self.spawn("adjust_provider.py", name, str(md_dir))

    def ln_manager(self, *args: str) -> subprocess.CompletedProcess[str]:
        """`ln_manager ARGS...` against this manager, to its end."""
        return subprocess.run([sys.executable, "-m", "links_and_nodes.manager", *args],
                              capture_output=True, text=True, env=self.client_env(),
                              timeout=LIMIT)


@pytest.fixture
def lab(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Lab]:
    instance = f"i{os.getpid()}x{uuid.uuid4().hex[:8]}"
    with monkeypatch.context() as env:  # only the manager's environment has it
        env.setenv("LN_MESSAGE_DEFINITION_DIRS", str(MDS))
        manager = launch.start_manager(instance, tmp_path / "run", tmp_path / "manager.log")
    lab = Lab(manager)
    try:
        yield lab
    finally:
        stop(lab.procs)
        code = manager.stop()
    assert code == 0, manager.log.read_text(errors="replace")
    assert segments(instance) == []
