"""Helpers of the Zenoh bridge tests: sites, each a links_and_nodes instance (its own manager)
in its own lab host (tests/python/netlab.py: network namespace, /dev/shm, runtime dir), with
ln_zenoh bridges, zb_peer.py clients and zb_raw.py plain Zenoh sessions run in them.

The tests need the Python package zenoh (eclipse-zenoh, requirements-dev.txt): without it they
skip (the Debian package build, which has no python3 package of it), except under CI=1, where
that is a failure.  No test directory has an __init__.py here: a package named `zenoh` would
hide the real one.
"""

from __future__ import annotations

import json
import os
import re
import signal
import sys
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from buildtree import missing_test_tool
from netlab import Host, HostProcess, NetLab
from polling import wait_for

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
MD_DIR = HERE / "md"  # zbtest/sample, zbtest/other, zbtest/echo
MD_CHANGED = HERE / "md_changed"  # zbtest/sample with another layout
MANAGER_PORT = 54414  # every host has its own network stack
ZENOH_PORT = 7447
_GOT = re.compile(r"got (\d+) (\d+) (OK|BAD)$")


def require_zenoh() -> None:
    try:
        import zenoh  # noqa: F401
    except ImportError:
        missing_test_tool("the Python package zenoh (eclipse-zenoh, requirements-dev.txt)")


def require_native_core() -> None:
    """ln_zenoh's native core (built by `scons` where cargo is installed: in CI always)."""
    from links_and_nodes.zenoh_bridge.native import CoreUnavailable, load_core

    try:
        load_core()
    except CoreUnavailable as exc:
        missing_test_tool(f"ln_zenoh's native core (scons builds it with cargo): {exc}")


class Site:
    """A links_and_nodes instance named `name` on lab host `host`; its bridge's prefix is
    ln/<name>, its Zenoh endpoint (when it listens) tcp/<address>:7447; its bridges carry topic
    samples through the native core if `native`, else through Python."""

    def __init__(self, lab: NetLab, host: Host, name: str, native: bool = False) -> None:
        self.lab = lab
        self.host = host
        self.name = name
        self.native = native
        self.md_dirs = [MD_DIR]  # LN_MESSAGE_DEFINITION_DIRS of what runs here, first wins
        self.instance = f"zb{os.getpid()}{name}{uuid.uuid4().hex[:6]}"
        self.prefix = f"ln/{name}"
        self.endpoint = f"tcp/{host.address}:{ZENOH_PORT}"
        self.manager: HostProcess | None = None
        self.procs: list[HostProcess] = []
        self._serial = 0

    @property
    def address(self) -> str:
        return f"127.0.0.1:{MANAGER_PORT}"

    def env(self) -> dict[str, str]:
        env = self.host.env()
        env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "python"), str(ROOT)])
        env["LN_MESSAGE_DEFINITION_DIRS"] = os.pathsep.join(map(str, self.md_dirs))
        env["LN_MANAGER"] = self.address
        env["LN_RECONNECT"] = "0"
        return env

    def log_name(self, what: str) -> str:
        self._serial += 1
        return f"{self.name}.{what}.{self._serial}.log"

    def popen(self, argv: list[str], what: str) -> HostProcess:
        proc = self.host.popen(argv, env=self.env(), log=self.log_name(what))
        self.procs.append(proc)
        return proc

    def start_manager(self, *extra: str, wait: bool = True) -> HostProcess:
        """Its ln_manager (with `extra` arguments); returns once it listens unless not `wait`."""
        self.manager = self.popen(
            [sys.executable, "-m", "links_and_nodes.manager", "--port", str(MANAGER_PORT),
             "--instance", self.instance, "--no-console", *extra], "manager")
        if wait:
            wait_log(self.manager, r" listening on ")
        return self.manager

    def bridge_argv(self, *args: str) -> list[str]:
        return [sys.executable, "-m", "links_and_nodes.zenoh_bridge.cli", "--prefix",
                self.prefix, "--poll", "0.2", "--stats-file", str(self.stats_path()),
                "--native", "on" if self.native else "off", *args]

    def bridge(self, *args: str, ready: bool = True) -> HostProcess:
        """ln_zenoh with `args`; returns once it says it is up (through the data path the site
        is for)."""
        proc = self.popen(self.bridge_argv(*args), "ln_zenoh")
        if ready:
            path = "the native core" if self.native else "Python"
            wait_log(proc, rf"bridge {re.escape(self.prefix)} up: .*; topic samples through "
                     rf"{path}$")
        return proc

    def peer(self, *args: str) -> HostProcess:
        return self.popen([sys.executable, str(HERE / "zb_peer.py"), *args], "peer")

    def raw(self, *args: str) -> HostProcess:
        return self.popen([sys.executable, str(HERE / "zb_raw.py"), *args], "raw")

    def stats_path(self) -> Path:
        return self.lab.directory / f"{self.name}.stats.json"

    def stats(self, bridge: HostProcess) -> dict[str, Any]:
        """The bridge's counters: SIGUSR1, then its --stats-file once rewritten."""
        path = self.stats_path()
        before = path.stat().st_mtime_ns if path.exists() else 0
        bridge.send_signal(signal.SIGUSR1)
        wait_for(lambda: path.exists() and path.stat().st_mtime_ns != before,
                 f"{self.name}'s bridge to write its statistics")
        return dict(json.loads(path.read_text()))

    def close(self) -> None:
        for proc in reversed(self.procs):
            if proc.poll() is None:
                proc.terminate()
        for proc in reversed(self.procs):
            try:
                proc.wait(timeout=15)
            except Exception:  # noqa: BLE001 - killed with the lab anyway
                proc.kill()


def log_text(proc: HostProcess) -> str:
    assert proc.log_path is not None
    return proc.log_path.read_text(errors="replace")


def wait_log(proc: HostProcess, pattern: str, timeout: float = 60.0) -> re.Match[str]:
    """The first match of `pattern` in the process's log; fails if it exits first."""
    regex = re.compile(pattern, re.M)

    def found() -> re.Match[str] | None:
        m = regex.search(log_text(proc))
        if m is None and proc.poll() is not None:
            pytest.fail(f"{proc.args[-1]} exited ({proc.returncode}) before /{pattern}/:\n"
                        f"{log_text(proc)[-3000:]}")
        return m

    return wait_for(found, f"/{pattern}/ in {proc.log_path}", timeout)  # type: ignore[return-value]


def received(proc: HostProcess) -> list[tuple[int, int, bool]]:
    """(local seq, counter, value ok) of every sample a `zb_peer.py sub` printed."""
    return [(int(m[1]), int(m[2]), m[3] == "OK")
            for m in map(_GOT.match, log_text(proc).splitlines()) if m]


def start_managers(*sites: Site) -> None:
    """Start the sites' managers together; return once all listen."""
    for site in sites:
        site.start_manager(wait=False)
    for site in sites:
        assert site.manager is not None
        wait_log(site.manager, r" listening on ")


def site_pair(netlab: NetLab, native: bool) -> Iterator[tuple[Site, Site]]:
    """Sites a (host a, 10.77.0.1) and b (host b, 10.77.0.2), closed afterwards; nothing
    started yet.  Their bridges carry topic samples through the native core or Python."""
    require_zenoh()
    if native:
        require_native_core()
    a, b = (Site(netlab, netlab[h], h, native=native) for h in ("a", "b"))
    try:
        yield a, b
    finally:
        b.close()
        a.close()
