"""Running one case of the network benchmark in a NetLab (tests/python/netlab.py): raw
socket pairs between hosts a and b, and ln pairs that an ln_manager starts through the
ln_daemons, either with both processes on one host (the manager there too) or with `ping` on
a, `pong` on b and the manager on mgr; the ln_daemons' CPU time.  Knows how to start and
collect things, not what the numbers mean (network_report.py)."""

from __future__ import annotations

import json
import os
import re
import selectors
import signal
import subprocess
import sys
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from netlab import DaemonProc, Host, NetLab

REPO = Path(__file__).resolve().parents[2]
CASE_TIMEOUT = 600.0  # seconds for one case; a stuck case is stopped and reported
READY_TIMEOUT = 60.0  # seconds for a server or a manager to come up
RAW_PORT = 5201  # the raw servers' port on host b (each host has its own stack)
MANAGER_PORT = 54414
DATA_PORT = 54377  # ln_daemon's forwarding port, where the daemon has one


class CaseError(Exception):
    """One measurement failed; the run goes on and the report says why."""


def json_line(text: str, what: str) -> dict[str, Any]:
    """The last line of `text` that is a JSON object."""
    for line in reversed(text.splitlines()):
        if line.startswith("{"):
            return json.loads(line)  # type: ignore[no-any-return]
    raise CaseError(f"{what} printed no result: {text.strip()[-300:]!r}")


def ln_env(host: Host) -> dict[str, str]:
    """The host's environment, able to import links_and_nodes from this checkout."""
    path = os.pathsep.join(
        p for p in (str(REPO / "python"), str(REPO), os.environ.get("PYTHONPATH", "")) if p
    )
    return {**host.env(), "PYTHONPATH": path, "PYTHONUNBUFFERED": "1"}


def multihost_missing(daemon_exe: str) -> str | None:
    """None if the multi-host system is there to measure, else what is missing.  Forwarding
    lives in ln_daemon (its data port); add further checks here as the pieces land."""
    text = subprocess.run([daemon_exe, "--help"], capture_output=True, text=True).stdout
    if "--data-port" not in text:
        return "ln_daemon has no --data-port (host-to-host forwarding is not built)"
    return None


def process_cpu_s(pid: int) -> float:
    """CPU seconds (user + system, all its threads, not its children) that process `pid` has
    used so far, from /proc/PID/stat."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()  # the name in (...) may hold spaces
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")  # utime, stime


@dataclass
class Proc:
    """One process of a managed case: its .lnc entry and where its output goes."""

    name: str
    node: str
    argv: list[str]
    ready: bool = False  # prints "ready" when it may be used (the others depend on it)
    log: Path = field(default=Path())


class Lab:
    """The run's lab: hosts a, b and mgr, an ln_daemon on a and b (with a data port where
    the daemon has one), and the programs of bench/network.  `security`: the instance's
    `security` level its managers write (None: the default, authenticate)."""

    security: str | None = None

    def __init__(
        self,
        lab: NetLab,
        bin_dir: Path,
        force_multihost: bool = False,
        daemon_args: tuple[str, ...] = (),
        host_args: dict[str, tuple[str, ...]] | None = None,
    ) -> None:
        """`host_args`: further daemon options of one host (e.g. bench/pull's
        --advertise-data-port on b, whose data port sits behind a relay)."""
        from links_and_nodes.manager.processes.daemon_launch import daemon_executable

        self.lab = lab
        self.a, self.b = lab["a"], lab["b"]
        self.mgr = lab.add_host("mgr")
        self.bin = bin_dir
        self.serial = 0
        missing = multihost_missing(daemon_executable())
        self.multihost_missing = None if force_multihost else missing
        data_port = None if missing else DATA_PORT
        self.daemons: dict[str, DaemonProc] = {
            h.name: h.start_daemon(
                lab.key_file,
                data_port=data_port,
                extra_args=daemon_args + (host_args or {}).get(h.name, ()),
            )
            for h in (self.a, self.b)
        }

    def daemon_cpu_s(self) -> dict[str, float]:
        """CPU seconds each host's ln_daemon has used so far, by host name: the daemons live
        through every case, so a case's share is the difference around it."""
        return {name: process_cpu_s(d.pid) for name, d in self.daemons.items()}

    def path(self, stem: str) -> Path:
        self.serial += 1
        return self.lab.directory / f"{stem}{self.serial}"

    def prog(self, name: str) -> str:
        return str(self.bin / name)

    # ---- raw pairs ----------------------------------------------------------------------

    def raw_pair(self, server: list[str], client: list[str], what: str) -> tuple[str, str]:
        """Start `server` on b, wait for its "ready", run `client` on a to its end, then
        let the server end (or stop it); both outputs."""
        srv = self.b.popen(server, stdout=subprocess.PIPE)
        try:
            assert srv.stdout is not None
            with selectors.DefaultSelector() as sel:
                sel.register(srv.stdout, selectors.EVENT_READ)
                line = srv.stdout.readline() if sel.select(READY_TIMEOUT) else ""
            if line.strip() != "ready":
                raise CaseError(
                    f"{what}: server did not start: {line.strip()!r} "
                    f"{srv.log_path and srv.log_path.read_text()[-300:]!r}"
                )
            try:
                cli = self.a.run(client, timeout=CASE_TIMEOUT)
            except subprocess.TimeoutExpired:
                raise CaseError(f"{what}: client did not finish in {CASE_TIMEOUT:.0f} s") from None
            if cli.returncode != 0:
                raise CaseError(
                    f"{what}: client exited with {cli.returncode}: {cli.stderr.strip()[-300:]}"
                )
            try:
                out, _ = srv.communicate(timeout=5.0)  # a stream server ends at EOF
            except subprocess.TimeoutExpired:
                srv.terminate()  # the UDP echo may have missed its end datagrams
                out, _ = srv.communicate(timeout=READY_TIMEOUT)
            return out, cli.stdout
        finally:
            if srv.poll() is None:
                srv.kill()
                srv.wait()
            if srv.stdout is not None:
                srv.stdout.close()

    # ---- ln pairs through a manager -----------------------------------------------------

    def managed(
        self, manager: Host, procs: list[Proc], results: list[str], what: str, extra: str = ""
    ) -> dict[str, dict[str, Any]]:
        """Run `procs` with an ln_manager on `manager` (`--start-all`; a process with
        `ready` is one the others depend on) until every process in `results` has printed its
        JSON line; then stop the manager, which stops the rest.  The JSON lines by name.
        `extra`: further .lnc sections (e.g. `topics`)."""
        local = manager is not self.mgr
        address = f"{'127.0.0.1' if local else manager.address}:{MANAGER_PORT}"
        instance = f"lnbench-net-{uuid.uuid4().hex[:8]}"
        config = self.path("case").with_suffix(".lnc")
        for proc in procs:
            proc.log = self.path(f"{proc.name}.out")
        config.write_text(self._config(instance, address, procs) + extra)
        argv = [
            sys.executable,
            "-m",
            "links_and_nodes.manager",
            "-c",
            str(config),
            "--start-all",
            "--no-console",
            "--exit-on-failure",
            "--log-level",
            "warning",
            "--daemon-key-file",
            str(self.lab.key_file),
        ]
        mgr = manager.popen(argv, env=ln_env(manager), log=f"{config.stem}.manager.log")
        got: dict[str, dict[str, Any]] = {}
        deadline = time.monotonic() + CASE_TIMEOUT
        try:
            while len(got) < len(results):
                for proc in procs:
                    if proc.name in results and proc.name not in got:
                        text = proc.log.read_text(errors="replace") if proc.log.exists() else ""
                        text = text[: text.rfind("\n") + 1]  # whole lines only
                        line = next((ln for ln in text.splitlines() if ln.startswith("{")), "")
                        if line:
                            got[proc.name] = json.loads(line)
                        elif re.search(r"^ln_\w+: ", text, re.M):  # its error, or libln's
                            raise CaseError(f"{what}: {proc.name}: {text.strip()[-300:]}")
                if mgr.poll() is not None and len(got) < len(results):
                    tails = [
                        f"{p.name}: {p.log.read_text(errors='replace').strip()[-200:]}"
                        for p in procs
                        if p.log.exists()
                    ]
                    log = mgr.log_path.read_text(errors="replace") if mgr.log_path else ""
                    raise CaseError(
                        f"{what}: {' | '.join(tails)} | ln_manager exited with "
                        f"{mgr.returncode}: {log.strip()[-300:]}"
                    )
                if time.monotonic() > deadline:
                    raise CaseError(f"{what}: no result in {CASE_TIMEOUT:.0f} s")
                time.sleep(0.05)
        finally:
            if mgr.poll() is None:
                mgr.send_signal(signal.SIGTERM)  # stops the processes through the daemons
            try:
                mgr.wait(READY_TIMEOUT)
            except subprocess.TimeoutExpired:
                mgr.kill()
                mgr.wait()
        return got

    def _config(self, instance: str, address: str, procs: list[Proc]) -> str:
        port = self.daemons["a"].port
        lines = [
            "instance",
            f"name: {instance}",
            f"manager: {address}",
            *([f"security: {self.security}"] if self.security else []),
            "",
            "hosts",
            f"localhost: daemon_port:{port}",
        ]
        lines += [f"{h.name}: eth0:{h.address}, daemon_port:{port}" for h in (self.a, self.b)]
        ready = [p.name for p in procs if p.ready]
        for proc in procs:
            lines += [
                "",
                f"process {proc.name}",
                f"    node: {proc.node}",
                f"    command: {' '.join(proc.argv)}",
                f"    output_logfile: {proc.log}",
                "    flags: no_pty, no_error_on_successful_stop",
            ]
            if proc.ready:
                lines.append("    ready_regex: ^ready")
            elif ready:
                lines.append(f"    depends_on: {', '.join(ready)}")
        return "\n".join(lines) + "\n"

    def ln_placement(self, system: str) -> tuple[Host, str, str]:
        """(manager host, node of the measuring side, node of the echoing side)."""
        if system == "ln_local":
            return self.a, "localhost", "localhost"
        return self.mgr, "a", "b"

    def shm_left(self) -> dict[str, list[str]]:
        """Names in each host's /dev/shm, which the managers must have emptied."""
        return {
            h.name: sorted(os.listdir(h.path("/dev/shm")))
            for h in (self.a, self.b, self.mgr)
            if os.listdir(h.path("/dev/shm"))
        }
