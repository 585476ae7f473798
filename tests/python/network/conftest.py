"""A multi-host system for the network tests: a NetLab with hosts a, b, c (each its own
network stack, /dev/shm and ln_daemon) and mgr (the manager), a generated .lnc placing
netclient.py programs on the hosts, and the manager's scripting API reached inside mgr's
network.  Programs started outside the manager (to survive their daemon's death) run with
`System.client()`."""

from __future__ import annotations

import os
import re
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from netlab import Host, HostProcess, NetLab, in_netns
from polling import wait_for

from links_and_nodes.manager import connect

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
DAEMON_PORT = 54376
MANAGER_PORT = 54414
READY_TIMEOUT = 60.0  # an upper bound for processes to get ready, never a measurement
_GOT = re.compile(r"got (\d+) (\d+) (OK|BAD)")


class System:
    def __init__(self, lab: NetLab, tmp: Path) -> None:
        self.lab = lab
        self.tmp = tmp
        lab.add_host("c")
        lab.add_host("mgr")
        self.instance = f"net{os.getpid()}_{tmp.name[-12:]}".replace("-", "_")
        self.daemons = {}
        self.manager_proc: HostProcess | None = None
        self.mgr: Any = None
        self.clients: list[HostProcess] = []

    @property
    def address(self) -> str:
        return f"{self.lab['mgr'].address}:{MANAGER_PORT}"

    def env(self, host: Host) -> dict[str, str]:
        env = host.env()
        env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "python"), str(ROOT)])
        env["LN_ARBITER_PORT"] = str(DAEMON_PORT)
        env["LN_MESSAGE_DEFINITION_DIRS"] = str(HERE / "md")
        return env

    def start_daemon(self, name: str, *args: str) -> Any:
        daemon = self.lab[name].start_daemon(self.lab.key_file, port=DAEMON_PORT,
                                             extra_args=args)
        self.daemons[name] = daemon
        return daemon

    def start_daemons(self, hosts: str = "abc") -> None:
        """A daemon with the default options on each of these hosts."""
        for host in hosts:
            self.start_daemon(host)

    def run(self, lnc: Path) -> Any:
        """The manager of `lnc` with every process started and ready."""
        mgr = self.start_manager(lnc)
        mgr.start("all")
        mgr.wait_ready("all", timeout=READY_TIMEOUT)
        return mgr

    def lnc(self, processes: str, extra: str = "") -> Path:
        hosts = "\n".join(f"{h}: eth0: {self.lab[h].address}" for h in ("a", "b", "c"))
        text = f"""instance
name: {self.instance}
manager: {self.address}

hosts
{hosts}

add_message_definition_dir: {HERE / 'md'}

{extra}

{processes}
"""
        path = self.tmp / "system.lnc"
        path.write_text(text)
        return path

    @staticmethod
    def process(name: str, node: str, args: str, ready: str, depends_on: str = "") -> str:
        depends = f"\n    depends_on: {depends_on}" if depends_on else ""
        return f"""process {name}
    node: {node}{depends}
    command: {sys.executable} {HERE / 'netclient.py'} {args}
    pass_environment: PYTHONPATH
    ready_regex: ^{ready}
    term_timeout: 2
"""

    def start_manager(self, lnc: Path) -> Any:
        mgr_host = self.lab["mgr"]
        self.manager_proc = mgr_host.popen(
            [sys.executable, "-m", "links_and_nodes.manager", "-c", str(lnc),
             "--no-console", "--daemon-key-file", str(self.lab.key_file)],
            env=self.env(mgr_host), log="manager.log")
        self.mgr = wait_for(lambda: self._connect(), "the manager to listen", timeout=30)
        return self.mgr

    def _connect(self) -> Any:
        assert self.manager_proc is not None
        if self.manager_proc.poll() is not None:
            pytest.fail(f"the manager exited: {self.log('manager.log')}")
        try:
            return in_netns(self.lab["mgr"].netns, lambda: connect(self.address))
        except Exception:
            return None

    def log(self, name: str) -> str:
        return (self.lab.directory / name).read_text(errors="replace")[-4000:]

    def client(self, host: str, *args: str) -> HostProcess:
        """netclient.py on `host`, outside the manager (its output in a log file)."""
        env = self.env(self.lab[host])
        env["LN_MANAGER"] = self.address
        proc = self.lab[host].popen([sys.executable, str(HERE / "netclient.py"), *args],
                                    env=env, log=f"client.{host}.{len(self.clients)}.log")
        self.clients.append(proc)
        return proc

    def output(self, name: str) -> list[str]:
        return list(self.mgr.output(name, 10000))

    @staticmethod
    def received(lines: list[str]) -> list[tuple[int, int, bool]]:
        """(seq, counter, pattern ok) of every "got" line."""
        return [(int(m[1]), int(m[2]), m[3] == "OK") for m in map(_GOT.match, lines) if m]

    def client_received(self, proc: HostProcess) -> list[tuple[int, int, bool]]:
        assert proc.log_path is not None
        return self.received(proc.log_path.read_text(errors="replace").splitlines())

    def stream(self, topic: str, src: str, dst: str) -> dict[str, Any] | None:
        for s in self.mgr.network()["streams"]:
            if (s["topic"], s["src"], s["dst"]) == (topic, src, dst):
                return s  # type: ignore[no-any-return]
        return None

    def close(self) -> None:
        if self.mgr is not None:
            try:
                self.mgr.quit()
            except Exception:
                pass
            self.mgr.close()
        if self.manager_proc is not None:
            try:
                self.manager_proc.wait(timeout=30)
            except Exception:
                self.manager_proc.kill()
        for proc in self.clients:
            proc.kill()
            proc.wait()


@pytest.fixture
def system(netlab: NetLab, tmp_path: Path) -> Iterator[System]:
    sys_ = System(netlab, tmp_path)
    try:
        yield sys_
    finally:
        sys_.close()
