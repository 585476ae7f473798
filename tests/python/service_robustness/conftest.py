"""Fixtures of the service robustness tests: a private ln_manager per test (unique instance,
free port, own runtime dir) and the C echo provider/caller `service_stress` built by SCons.
Every tool is stopped at the end of its test."""

from __future__ import annotations

import json
import subprocess
import uuid
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest
from buildtree import build_dir

from links_and_nodes.manager.frontends import launch
from links_and_nodes.manager.frontends.launch import ManagerProcess

REPO = Path(__file__).resolve().parents[3]
STRESS = build_dir() / "tests" / "c" / "tools" / "service_stress"
LIMIT = 60.0  # upper bound for anything to happen, never a measurement


@dataclass
class Setup:
    manager: ManagerProcess
    runtime: Path
    tools: list[subprocess.Popen[str]] = field(default_factory=list)

    def run(self, *args: str, stdin: int | None = subprocess.DEVNULL,
            env: dict[str, str] | None = None) -> subprocess.Popen[str]:
        """service_stress with `args`; `env` adds to the manager's environment."""
        if not STRESS.exists():
            pytest.fail(f"{STRESS} is missing: run scons first")
        proc = subprocess.Popen([str(STRESS), *args], stdin=stdin, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True,
                                env={**self.manager.env, **(env or {})})
        self.tools.append(proc)
        return proc

    def provider(self, name: str, *mode: str) -> subprocess.Popen[str]:
        """A provider of lntest/echo that runs until its stdin closes; returns once ready."""
        proc = self.run("provide", name, *mode, stdin=subprocess.PIPE)
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert line.strip() == "ready", f"provider did not start: {line!r} {proc.stderr.read()}"
        return proc

    def call(self, *args: str) -> dict[str, Any]:
        """Runs `service_stress call ...` to the end; its JSON summary."""
        proc = self.run("call", *args)
        out, err = proc.communicate(timeout=LIMIT * 3)
        assert out.strip(), f"caller printed nothing: {err}"
        return json.loads(out.strip().splitlines()[-1])

    def sockets(self) -> list[Path]:
        return sorted(self.runtime.glob("svc.*.sock"))


def private_manager(tmp_path: Path, *args: str) -> Iterator[Setup]:
    """A Setup around a private manager started with `args`; its tools and it are stopped
    when the generator is closed."""
    instance = f"svc-{uuid.uuid4().hex[:12]}"
    runtime = tmp_path / "run"
    manager = launch.start_manager(instance, runtime, tmp_path / "manager.log", *args)
    s = Setup(manager, runtime)
    try:
        yield s
    finally:
        for proc in s.tools:
            if proc.poll() is None:
                proc.kill()
            proc.wait()
            for stream in (proc.stdin, proc.stdout, proc.stderr):
                if stream is not None:
                    stream.close()
        manager.stop()


@pytest.fixture
def setup(tmp_path: Path) -> Iterator[Setup]:
    yield from private_manager(tmp_path)


def stop(proc: subprocess.Popen[str]) -> int:
    """Close a provider's stdin (its signal to unregister and exit) and wait for it."""
    assert proc.stdin is not None
    proc.stdin.close()
    return proc.wait(timeout=LIMIT)
