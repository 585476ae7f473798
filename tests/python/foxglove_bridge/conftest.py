"""Fixtures of the ln_foxglove tests: one real system per test module, run by `ln_manager -c`
with its own instance, manager port, ln_daemon port, key file and runtime directory.  Its
processes, started by the daemon: the C publisher tests/c/tools/topic_tool (robot/joint_state
on fx.joint at 1 kHz, and on fx.fast for the rate limit), the Python publisher of the
introspection tests (lntest/probe on fx.probe: nested, float32, char fields; its md directory
known to the manager only through this process), the C provider service_tool (fx.gains,
robot/set_gains) and ln_foxglove itself, as a process of the configuration.

foxglove-sdk (an optional extra of the package) and websockets (the test's client) are test
tools here: missing, the tests fail under CI=1 and skip elsewhere."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from buildtree import build_dir, missing_test_tool
from polling import free_daemon_port, free_port, pids_with, wait_for

from links_and_nodes.tools import scripting

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[2]
PROBE = REPO / "tests" / "python" / "introspection" / "probe_publisher.py"
PROBE_MDS = REPO / "tests" / "fixtures" / "md" / "introspect"
LIMIT = 60.0  # upper bound for anything to happen, never a measurement
FAST_RATE = 10  # Hz: the rate limit of fx.fast
QUEUE = 64  # buffers of fx.joint's queued channel


def require_tools() -> None:
    try:
        import foxglove  # noqa: F401
    except ImportError:
        missing_test_tool("the Python package foxglove (foxglove-sdk, requirements-dev.txt)")
    try:
        import websockets.asyncio.client  # noqa: F401
    except ImportError:
        missing_test_tool("the Python package websockets (requirements-dev.txt)")


@dataclass
class System:
    instance: str
    manager_port: int
    foxglove_port: int
    tmp: Path
    proc: subprocess.Popen[str]

    def connect(self) -> scripting.Manager:
        return scripting.connect(f"127.0.0.1:{self.manager_port}", timeout=LIMIT)

    def bridge_output(self) -> str:
        with self.connect() as mgr:
            return "\n".join(mgr.output("foxglove", 1000))


def config(instance: str, manager_port: int, foxglove_port: int) -> str:
    tools = build_dir() / "tests" / "c" / "tools"
    py = sys.executable
    return f"""\
instance
name: {instance}
manager: 127.0.0.1:{manager_port}

process pub
command: {tools}/topic_tool pub-loop fx.joint 1000
ready_on_topic: fx.joint
term_timeout: 2

process fast
command: {tools}/topic_tool pub-loop fx.fast 1000
ready_on_topic: fx.fast
term_timeout: 2

process probe
command: {py} {PROBE} 127.0.0.1:{manager_port} fx.probe 0.01 {PROBE_MDS}
add_message_definition_dir: {PROBE_MDS}
ready_on_topic: fx.probe
term_timeout: 2

process gains
command: {tools}/service_tool provide fx.gains --md robot/set_gains
ready_on_service: fx.gains
term_timeout: 2

process foxglove
command: {py} -m links_and_nodes.foxglove_bridge.cli --port {foxglove_port} --poll 0.2 -v \
--topic fx.joint,queued={QUEUE} --topic fx.fast,rate={FAST_RATE} --topic fx.*
ready_regex: ^ln_foxglove: serving ws://
term_timeout: 5
"""


@pytest.fixture(scope="module")
def system(tmp_path_factory: pytest.TempPathFactory) -> Iterator[System]:
    require_tools()
    tmp = tmp_path_factory.mktemp("foxglove")
    instance = f"fx-{uuid.uuid4().hex[:10]}"
    daemon_port = free_daemon_port()
    env = {**os.environ, "LN_RUNTIME_DIR": str(tmp / "run"),
           "LN_DAEMON_KEY_FILE": str(tmp / "keys" / "daemon.key"),
           "LN_ARBITER_PORT": str(daemon_port), "PYTHONUNBUFFERED": "1"}
    manager_port, foxglove_port = free_port(), free_port()
    path = tmp / "foxglove.lnc"
    path.write_text(config(instance, manager_port, foxglove_port))
    with open(tmp / "manager.log", "w") as log:
        proc = subprocess.Popen([sys.executable, "-m", "links_and_nodes.manager", "-c",
                                 str(path), "--no-console"], stdin=subprocess.DEVNULL,
                                stdout=subprocess.PIPE, stderr=log, text=True, env=env)
    system = System(instance, manager_port, foxglove_port, tmp, proc)
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert "listening on" in line, (line, (tmp / "manager.log").read_text())
        with system.connect() as mgr:
            mgr.start("all")
            mgr.wait_ready("all", LIMIT)
        yield system
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(timeout=LIMIT)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        if proc.stdout is not None:
            proc.stdout.close()
        for pid in pids_with(f"--port\0{daemon_port}\0") + pids_with(instance):
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)


__all__ = ["LIMIT", "System", "wait_for"]
