"""Process plumbing of the topic benchmark: a private ln_manager (unique instance, free port,
log in a file), child processes pinned to one CPU or left to the scheduler, and the probes
the report prints (pinning).  Knows nothing about what is measured."""

from __future__ import annotations

import os
import platform
import subprocess
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from links_and_nodes.manager.frontends.launch import ManagerProcess, segments, start_manager

CHILD_TIMEOUT = 600.0  # seconds for one child; a stuck case is killed and reported
SAMPLE_PERIOD = 0.02  # seconds between looks at which CPU each side of a pair last ran on


class CaseError(Exception):
    """One measurement failed; the run goes on and the report says why."""


@dataclass
class Manager:
    """The benchmark's private manager (a thin layer over links_and_nodes.manager.frontends.launch)."""

    process: ManagerProcess

    @property
    def address(self) -> str:
        return self.process.address

    @classmethod
    def start(cls, tmp: Path) -> Manager:
        instance = f"bench{os.getpid()}x{uuid.uuid4().hex[:8]}"
        return cls(start_manager(instance, tmp / "runtime", tmp / "manager.log",
                                 "--log-level", "warning"))

    def stop(self) -> list[str]:
        """Terminate the manager; returns the segments of the instance it left behind
        (removed here, so a bug does not leak memory)."""
        self.process.stop()
        left = segments(self.process.instance)
        for name in left:
            Path("/dev/shm", name).unlink(missing_ok=True)
        return left


def run_facts(started: str, quick: bool) -> dict[str, Any]:
    """The head of a result file: when, how, and on what machine the run was made."""
    return {"started": started, "quick": quick, "machine": platform.machine(),
            "kernel": platform.release(), "python_version": platform.python_version(),
            "cpu_count": os.cpu_count()}


def warn_leftover(leftover: list[str]) -> None:
    """Say which segments the benchmark's manager left behind (already removed)."""
    if leftover:
        print(f"\nwarning: the manager left {len(leftover)} segment(s) behind (removed): "
              f"{', '.join(leftover)}")


def can_pin(cpus: list[int]) -> str | None:
    """None if this process may pin itself (and so its children) to each of `cpus`, else
    why not."""
    before = os.sched_getaffinity(0)
    try:
        for cpu in cpus:
            os.sched_setaffinity(0, {cpu})
    except OSError as exc:
        return f"sched_setaffinity({cpu}) failed: {exc.strerror}"
    finally:
        os.sched_setaffinity(0, before)
    return None


def last_cpu(pid: int | None) -> int | None:
    """The CPU a process last ran on (field 39 of /proc/PID/stat); None if it is gone."""
    try:
        return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[36])
    except (OSError, IndexError, ValueError):
        return None


def first_child(pid: int) -> int | None:
    try:
        children = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
    except OSError:
        return None
    return int(children[0]) if children else None


class Runner:
    """Starts the benchmark programs with the manager's address, one CPU or none."""

    def __init__(self, tmp: Path, env: dict[str, str]) -> None:
        self.tmp = tmp
        self.env = env
        self.children: list[subprocess.Popen[str]] = []
        self.serial = 0
        self.same_cpu: float | None = None  # share of samples with both sides on one CPU

    def path(self, stem: str) -> Path:
        self.serial += 1
        return self.tmp / f"{stem}{self.serial}"

    def spawn(self, argv: list[str], cpu: int | None) -> subprocess.Popen[str]:
        pin: Callable[[], None] | None = None
        if cpu is not None:
            def pin() -> None:
                os.sched_setaffinity(0, {cpu})
        err = open(self.path("stderr"), "w+")  # closed in finish()
        proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=err, text=True,
                                env=self.env, preexec_fn=pin)
        proc.err_file = err  # type: ignore[attr-defined]
        self.children.append(proc)
        return proc

    def watch(self, proc: subprocess.Popen[str], partner: Callable[[], int | None]) -> None:
        """Until `proc` exits, sample whether it and its partner last ran on the same CPU:
        with the scheduler's placement that decides whether a wake-up crosses CPUs."""
        deadline = time.monotonic() + CHILD_TIMEOUT
        same = total = 0
        while proc.poll() is None and time.monotonic() < deadline:
            a, b = last_cpu(proc.pid), last_cpu(partner())
            if a is not None and b is not None:
                total += 1
                same += a == b
            time.sleep(SAMPLE_PERIOD)
        self.same_cpu = same / total if total else None

    def finish(self, proc: subprocess.Popen[str], what: str) -> str:
        """Wait for a child; its stdout, or CaseError with the end of its stderr."""
        try:
            out, _ = proc.communicate(timeout=CHILD_TIMEOUT)
        except subprocess.TimeoutExpired:
            proc.kill()
            out, _ = proc.communicate()
        err = proc.err_file  # type: ignore[attr-defined]
        err.seek(0)
        text = err.read()
        err.close()
        self.children.remove(proc)
        if proc.returncode != 0:
            raise CaseError(f"{what} exited with {proc.returncode}: {text.strip()[-500:]}")
        return out

    def single(self, argv: list[str], cpu: int | None) -> str:
        """Run a program that forks its partner; sets same_cpu."""
        proc = self.spawn(argv, cpu)
        self.watch(proc, lambda: first_child(proc.pid))
        return self.finish(proc, Path(argv[0]).name)

    def pair(self, server: list[str], client: list[str], cpus: tuple[int | None, int | None],
             what: str) -> tuple[str, str]:
        """Start `server` (on cpus[0]), wait for its "ready", then run `client` (on cpus[1]);
        both outputs; sets same_cpu."""
        srv = self.spawn(server, cpus[0])
        assert srv.stdout is not None
        line = srv.stdout.readline()
        if line.strip() != "ready":
            self.kill_all()
            raise CaseError(f"{what}: server did not start: {line.strip()!r}")
        try:
            cli = self.spawn(client, cpus[1])
            self.watch(cli, lambda: srv.pid)
            client_out = self.finish(cli, f"{what}: client")
        except CaseError:
            self.kill_all()
            raise
        return self.finish(srv, f"{what}: server"), client_out

    def kill_all(self) -> None:
        for proc in list(self.children):
            proc.kill()
            try:
                self.finish(proc, "killed")
            except CaseError:
                pass
