"""A lab of emulated hosts on one machine for multi-host tests and benchmarks: each host is a
network namespace joined to a private Linux bridge by a veth pair, with its own /dev/shm,
/tmp/ln-<uid>, hostname, /etc/hosts and LN_HOST_ID, so that nothing host-local leaks between
hosts.  Needs root (or CAP_SYS_ADMIN + CAP_NET_ADMIN); netlab_available() says why not.

    with NetLab(tmp_path) as lab:             # hosts a (10.77.0.1) and b (10.77.0.2)
        mgr = lab.add_host("mgr")             # 10.77.0.3
        daemon = lab["a"].start_daemon(lab.key_file)
        mgr.run([sys.executable, "client.py", daemon.address])

Every process of a host is started with `nsenter --target ANCHOR --mount --net --uts --ipc`
(ANCHOR: the host's anchor process, which holds its namespaces).  Leaving the `with` block,
also on an exception or Ctrl-C, kills every process in the lab's namespaces and deletes
them; a new lab first deletes the namespaces of labs whose creator has died.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import itertools
import os
import re
import selectors
import shlex
import shutil
import signal
import socket
import struct
import subprocess
import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar

PREFIX = "lnlab"  # every namespace of a lab is named lnlab<creator pid>x<serial>-<part>
SUBNET = "10.77.0"  # host number i gets SUBNET.i/24; each lab has its own bridge
WAIT = 60.0  # seconds; only ever an upper bound while waiting for something to happen
DAEMON_PORT = 54376  # ln_daemon's default port; every host has its own network stack
# Variables of the caller that would make hosts share state or reach the wrong manager.
_DROPPED_ENV = ("LN_RUNTIME_DIR", "XDG_RUNTIME_DIR", "LN_MANAGER", "LN_HOST_ID")
_NAME = re.compile(r"[a-z][a-z0-9-]{0,15}\Z")
_CLONE_NEWNET = 0x40000000
_serial = itertools.count(1)
T = TypeVar("T")


class NetLabError(Exception):
    """Setting up, using or tearing down the lab failed; the text says which command."""


def _run(argv: Sequence[str], what: str | None = None) -> str:
    proc = subprocess.run(list(argv), capture_output=True, text=True, timeout=WAIT,
                          stdin=subprocess.DEVNULL)
    if proc.returncode != 0:
        raise NetLabError(f"{what or ' '.join(argv)} failed ({proc.returncode}): "
                          f"{(proc.stderr or proc.stdout).strip()}")
    return proc.stdout


def _ip(*args: str) -> str:
    return _run(["ip", *args])


def namespaces() -> list[str]:
    """Names of every named network namespace (`ip netns list`)."""
    return [line.split()[0] for line in _ip("netns", "list").splitlines() if line.strip()]


def namespace_pids(netns: str) -> list[int]:
    """Pids of the processes in a named network namespace ([] if it is gone)."""
    proc = subprocess.run(["ip", "netns", "pids", netns], capture_output=True, text=True,
                          timeout=WAIT)
    return [int(p) for p in proc.stdout.split()] if proc.returncode == 0 else []


def _kill_namespace(netns: str) -> list[int]:
    """SIGKILL everything in `netns` until nothing is left, then delete it; the pids killed."""
    killed: list[int] = []
    deadline = time.monotonic() + WAIT
    while (pids := namespace_pids(netns)) and time.monotonic() < deadline:
        for pid in pids:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        killed += [p for p in pids if p not in killed]
        time.sleep(0.01)
    subprocess.run(["ip", "netns", "del", netns], capture_output=True, timeout=WAIT)
    return killed


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def sweep_stale(prefix: str = PREFIX) -> list[str]:
    """Delete the namespaces named <prefix><pid>x<serial>-... (and kill the processes in them)
    whose creating process <pid> is dead: what a killed run left.  Returns the names deleted."""
    swept = []
    pattern = re.compile(rf"{re.escape(prefix)}([0-9]+)x[0-9]+-")
    for netns in namespaces():
        m = pattern.match(netns)
        if m and not _pid_alive(int(m.group(1))):
            _kill_namespace(netns)
            swept.append(netns)
    return swept


@functools.cache
def netlab_available() -> str | None:
    """None if a lab can be built here (tried once per process, on a throw-away namespace),
    else the reason it cannot."""
    missing = [tool for tool in ("ip", "nsenter", "unshare") if shutil.which(tool) is None]
    if missing:
        return f"{', '.join(missing)} not found on PATH"
    netns = f"{PREFIX}{os.getpid()}x{next(_serial)}-probe"
    try:
        _ip("netns", "add", netns)
    except NetLabError as exc:
        return f"cannot create a network namespace ({exc}); the lab needs root"
    try:
        _ip("-n", netns, "link", "add", "br0", "type", "bridge")
        _ip("-n", netns, "link", "add", "v0", "type", "veth", "peer", "name", "v1")
        _run(["ip", "netns", "exec", netns, "unshare", "--mount", "--uts", "--ipc",
              "--propagation", "private", "sh", "-c", "mount -t tmpfs tmpfs /dev/shm"],
             "a private /dev/shm (unshare --mount; mount -t tmpfs)")
    except NetLabError as exc:
        return str(exc)
    finally:
        subprocess.run(["ip", "netns", "del", netns], capture_output=True, timeout=WAIT)
    return None


def in_netns(netns: str, fn: Callable[[], T]) -> T:
    """Call `fn` in a short-lived thread that has joined the network namespace `netns`: the
    sockets it creates belong to that namespace for their whole life."""
    result: list[Any] = []

    def target() -> None:
        try:
            fd = os.open(f"/run/netns/{netns}", os.O_RDONLY | os.O_CLOEXEC)
            try:
                if _libc().setns(fd, _CLONE_NEWNET) != 0:
                    err = ctypes.get_errno()
                    raise OSError(err, f"setns({netns}): {os.strerror(err)}")
            finally:
                os.close(fd)
            result.append((True, fn()))
        except BaseException as exc:  # noqa: BLE001 - handed to the caller's thread
            result.append((False, exc))

    thread = threading.Thread(target=target, name=f"netns {netns}")
    thread.start()
    thread.join()
    ok, value = result[0]
    if not ok:
        raise value
    return value  # type: ignore[no-any-return]


@functools.cache
def _libc() -> ctypes.CDLL:
    return ctypes.CDLL(None, use_errno=True)


def _checksum(data: bytes) -> int:
    if len(data) % 2:
        data += b"\0"
    total = sum(struct.unpack(f"!{len(data) // 2}H", data))
    total = (total >> 16) + (total & 0xFFFF)
    total += total >> 16
    return ~total & 0xFFFF


class HostProcess(subprocess.Popen):  # type: ignore[type-arg]
    """A process started in a lab host; `log_path` holds its output unless it was piped."""

    host: Host
    log_path: Path | None


class DaemonProc:
    """An ln_daemon (`--foreground`) running in one lab host; its stdout and log go to
    `log_path`."""

    def __init__(self, host: Host, key_file: Path, port: int, data_port: int | None,
                 extra_args: Sequence[str]) -> None:
        self.host = host
        self.key_file = Path(key_file)
        self.port = port
        self.data_port = data_port
        self.extra_args = tuple(extra_args)
        self.log_path = host.lab.directory / f"{host.name}.ln_daemon-{port}.log"
        self.proc: HostProcess | None = None

    @property
    def pid(self) -> int:
        assert self.proc is not None
        return self.proc.pid

    @property
    def address(self) -> str:
        """HOST:PORT where managers on other lab hosts reach it."""
        return f"{self.host.address}:{self.port}"

    def argv(self) -> list[str]:
        from links_and_nodes.manager.processes.daemon_launch import daemon_executable

        argv = [daemon_executable(), "--port", str(self.port), "--key-file",
                str(self.key_file), "--foreground"]
        if self.data_port is not None:
            argv += ["--data-port", str(self.data_port)]
        return argv + list(self.extra_args)

    def start(self, timeout: float = WAIT) -> DaemonProc:
        """Start it and return once it listens: its ready line is in the log and a connection
        from inside the host to HOST_ADDRESS:PORT gets the daemon's hello."""
        if self.proc is not None and self.proc.poll() is None:
            raise NetLabError(f"ln_daemon on {self.host.name} is already running")
        offset = self.log_path.stat().st_size if self.log_path.exists() else 0
        self.proc = self.host.popen(self.argv(), log=self.log_path.name)
        deadline = time.monotonic() + timeout
        while True:
            text = self.log_path.read_bytes()[offset:].decode(errors="replace")
            m = re.search(r"ln_daemon: listening on \S+:([0-9]+) \(pid ([0-9]+)\)", text)
            if m:
                self.port = int(m.group(1))  # port 0 asked: the one it got, kept for restart
                break
            if self.proc.poll() is not None or time.monotonic() > deadline:
                self.kill()
                raise NetLabError(f"ln_daemon on {self.host.name} did not start:\n{text}")
            time.sleep(0.02)
        while not self.host.daemon_answers(self.host.address, self.port):
            if self.proc.poll() is not None or time.monotonic() > deadline:
                self.kill()
                raise NetLabError(f"ln_daemon on {self.host.name} does not answer on "
                                  f"{self.address}:\n{self.log_path.read_text()}")
            time.sleep(0.02)
        return self

    def running(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def terminate(self, timeout: float = WAIT) -> int | None:
        """SIGTERM as in production (it stops its processes, then exits); SIGKILL if it has
        not exited within `timeout`.  Its exit status."""
        if self.proc is None:
            return None
        if self.proc.poll() is None:
            self.proc.terminate()
        try:
            return self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            return self.kill()

    def kill(self) -> int | None:
        """SIGKILL: the daemon dies at once; the processes it supervised live on."""
        if self.proc is None:
            return None
        if self.proc.poll() is None:
            self.proc.kill()
        return self.proc.wait()

    def restart(self, timeout: float = WAIT) -> DaemonProc:
        """Stop it (SIGTERM) if it runs, then start it again on the same ports."""
        self.terminate(timeout)
        return self.start(timeout)


class Host:
    """One emulated host: network namespace `netns` with `eth0` at `address`, and the anchor
    process whose mount, UTS and IPC namespaces (private /dev/shm and /tmp/ln-<uid>, hostname
    = host_id) every process of the host joins."""

    def __init__(self, lab: NetLab, name: str, number: int) -> None:
        self.lab = lab
        self.name = name
        self.number = number
        self.address = f"{SUBNET}.{number}"
        self.netns = f"{lab.name}-{name}"
        self.host_id = f"{lab.name}-{name}"  # also its hostname
        self.switch_port = f"p{number}"  # the veth end on the bridge, in the switch namespace
        self.anchor: subprocess.Popen[str] | None = None

    def __repr__(self) -> str:
        return f"<Host {self.name} {self.address} netns={self.netns}>"

    # ---- setting up ---------------------------------------------------------------------------

    def _create(self) -> None:
        sw = self.lab.switch
        _ip("netns", "add", self.netns)
        _ip("-n", self.netns, "link", "add", "eth0", "type", "veth", "peer", "name",
            self.switch_port, "netns", sw)
        _ip("-n", sw, "link", "set", self.switch_port, "master", "br0", "up")
        _ip("-n", self.netns, "addr", "add", f"{self.address}/24", "dev", "eth0")
        _ip("-n", self.netns, "link", "set", "eth0", "up")
        _ip("-n", self.netns, "link", "set", "lo", "up")
        runtime = f"/tmp/ln-{os.getuid()}"
        script = "; ".join([
            "set -e",
            "mount -t tmpfs -o mode=1777 tmpfs /dev/shm",
            f"mkdir -p -m 0700 {runtime}",
            f"mount -t tmpfs -o mode=0700 tmpfs {runtime}",
            f"mount --bind {shlex.quote(str(self.lab.hosts_file))} /etc/hosts",
            f"echo {self.host_id} > /proc/sys/kernel/hostname",
            "echo ready",
            "exec sleep infinity",
        ])
        log = open(self.lab.directory / f"{self.name}.anchor.log", "w")  # noqa: SIM115
        try:
            self.anchor = subprocess.Popen(
                ["ip", "netns", "exec", self.netns, "unshare", "--mount", "--uts", "--ipc",
                 "--propagation", "private", "sh", "-c", script],
                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=log, text=True)
        finally:
            log.close()
        assert self.anchor.stdout is not None
        with selectors.DefaultSelector() as sel:
            sel.register(self.anchor.stdout, selectors.EVENT_READ)
            line = self.anchor.stdout.readline() if sel.select(WAIT) else ""
        self.anchor.stdout.close()
        if line.strip() != "ready":
            raise NetLabError(f"host {self.name}: the anchor did not start: "
                              f"{(self.lab.directory / f'{self.name}.anchor.log').read_text()}")

    # ---- processes ----------------------------------------------------------------------------

    def env(self) -> dict[str, str]:
        """The caller's environment without what would point outside the host (runtime
        directories, LN_MANAGER), with LN_HOST_ID of this host."""
        env = {k: v for k, v in os.environ.items() if k not in _DROPPED_ENV}
        env["LN_HOST_ID"] = self.host_id
        return env

    def command(self, argv: Sequence[str], cwd: str | os.PathLike[str] | None = None
                ) -> list[str]:
        """`argv` wrapped so that it runs in this host (nsenter execs it: same pid)."""
        assert self.anchor is not None, "the lab is not set up"
        return ["nsenter", f"--target={self.anchor.pid}", "--mount", "--net", "--uts", "--ipc",
                f"--wd={os.fspath(cwd) if cwd is not None else os.getcwd()}", "--",
                *map(os.fspath, argv)]

    def popen(self, argv: Sequence[str | os.PathLike[str]], *,
              env: Mapping[str, str] | None = None, log: str | None = None,
              stdin: Any = subprocess.DEVNULL, stdout: Any = None,
              cwd: str | os.PathLike[str] | None = None) -> HostProcess:
        """Start `argv` in this host with `env` (default: env()).  Unless `stdout` is given
        (e.g. subprocess.PIPE, text mode), stdout and stderr go to the file `log` (default
        <host>.<program>.<n>.log) in the lab's directory, appended; with `stdout`, stderr
        still goes to that file."""
        name = log or f"{self.name}.{Path(os.fspath(argv[0])).name}.{next(_serial)}.log"
        path = self.lab.directory / name
        with open(path, "a") as out:
            proc = HostProcess(self.command(argv, cwd),
                               env=dict(self.env() if env is None else env),
                               stdin=stdin, stdout=out if stdout is None else stdout,
                               stderr=out, text=True)
        proc.host = self
        proc.log_path = path
        self.lab.processes.append(proc)
        return proc

    def run(self, argv: Sequence[str | os.PathLike[str]], *,
            env: Mapping[str, str] | None = None, input: str | None = None,
            timeout: float = WAIT, check: bool = False,
            cwd: str | os.PathLike[str] | None = None) -> subprocess.CompletedProcess[str]:
        """Run `argv` in this host to its end; stdout and stderr captured as text.  `timeout`
        is an upper bound (the process is killed and TimeoutExpired raised)."""
        return subprocess.run(self.command(argv, cwd),
                              env=dict(self.env() if env is None else env),
                              input=input, capture_output=True, text=True, timeout=timeout,
                              check=check, stdin=None if input is not None else
                              subprocess.DEVNULL)

    def path(self, path: str | os.PathLike[str]) -> Path:
        """`path` as this host sees it (its /dev/shm, /tmp/ln-<uid>), readable from outside
        through its anchor's root."""
        assert self.anchor is not None
        return Path(f"/proc/{self.anchor.pid}/root") / Path(path).relative_to("/")

    def pids(self) -> list[int]:
        """Every process in this host (its network namespace), the anchor included."""
        return namespace_pids(self.netns)

    # ---- network ------------------------------------------------------------------------------

    def socket(self, family: int = socket.AF_INET, type: int = socket.SOCK_STREAM,
               proto: int = 0) -> socket.socket:
        """A socket of this host's network stack, usable from the calling process."""
        return in_netns(self.netns, lambda: socket.socket(family, type, proto))

    def connect(self, address: str, port: int, timeout: float = 5.0) -> socket.socket:
        """A TCP connection from this host to address:port (OSError if it cannot be made)."""
        sock = self.socket()
        try:
            sock.settimeout(timeout)
            sock.connect((address, port))
        except BaseException:
            sock.close()
            raise
        return sock

    def daemon_answers(self, address: str, port: int) -> bool:
        """True if an ln_daemon greets a connection from this host to address:port."""
        try:
            with self.connect(address, port) as sock:
                head = b""  # u32 length, u8 type (DAEMON_HELLO), u32 request, the magic
                while len(head) < 17:
                    chunk = sock.recv(17 - len(head))
                    if not chunk:
                        return False
                    head += chunk
        except OSError:
            return False
        return head[4] == 0x01 and head[9:17] == b"LNDAEMON"

    def ping(self, address: str, timeout: float = 2.0) -> bool:
        """One ICMP echo request from this host to `address`; True if the reply came within
        `timeout` (an upper bound: on the lab's bridge replies take microseconds)."""
        ident, seq, payload = os.getpid() & 0xFFFF, next(_serial) & 0xFFFF, os.urandom(16)
        head = struct.pack("!BBHHH", 8, 0, 0, ident, seq)
        packet = struct.pack("!BBHHH", 8, 0, _checksum(head + payload), ident, seq) + payload
        deadline = time.monotonic() + timeout
        with self.socket(socket.AF_INET, socket.SOCK_RAW, socket.IPPROTO_ICMP) as sock:
            try:
                sock.sendto(packet, (address, 0))
                while (left := deadline - time.monotonic()) > 0:
                    sock.settimeout(left)
                    data, source = sock.recvfrom(65535)
                    ihl = (data[0] & 0x0F) * 4
                    kind, _, _, rid, rseq = struct.unpack_from("!BBHHH", data, ihl)
                    if (kind == 0 and (rid, rseq) == (ident, seq) and source[0] == address
                            and data[ihl + 8:] == payload):
                        return True
            except OSError:  # timeout, or unreachable
                return False
        return False

    def disconnect(self) -> None:
        """Pull the cable: the host's port on the bridge goes down, so nothing gets in or out
        (packets are dropped, no error comes back).  The host keeps its address and routes."""
        _ip("-n", self.lab.switch, "link", "set", self.switch_port, "down")

    def reconnect(self) -> None:
        _ip("-n", self.lab.switch, "link", "set", self.switch_port, "up")

    # ---- ln_daemon ----------------------------------------------------------------------------

    def start_daemon(self, key_file: str | os.PathLike[str] | None = None, *,
                     port: int = DAEMON_PORT, data_port: int | None = None,
                     extra_args: Sequence[str] = ()) -> DaemonProc:
        """Run the project's ln_daemon (daemon_launch.daemon_executable()) here, listening on
        every interface at `port` (0: any free one), with `key_file` (default: the lab's);
        `data_port`, if given, is passed as --data-port.  Returns once it answers."""
        daemon = DaemonProc(self, Path(key_file) if key_file else self.lab.key_file, port,
                            data_port, extra_args)
        self.lab.daemons.append(daemon)
        return daemon.start()


class NetLab:
    """Hosts on one private bridge (namespace `switch`), set up on entering the `with` block
    and removed, with everything running in them, on leaving it.  `directory` receives the
    logs, the key file and the lab's /etc/hosts."""

    def __init__(self, directory: str | os.PathLike[str],
                 hosts: Iterable[str] = ("a", "b")) -> None:
        self.directory = Path(directory)
        self.name = f"{PREFIX}{os.getpid()}x{next(_serial)}"
        self.switch = f"{self.name}-sw"
        self.hosts: dict[str, Host] = {}
        self.processes: list[HostProcess] = []
        self.daemons: list[DaemonProc] = []
        self.hosts_file = self.directory / "hosts"
        self._initial = list(hosts)
        self._key_file: Path | None = None
        self._open = False

    def __enter__(self) -> NetLab:
        try:
            self.directory.mkdir(parents=True, exist_ok=True)
            sweep_stale()
            self._open = True
            _ip("netns", "add", self.switch)
            _ip("-n", self.switch, "link", "add", "br0", "type", "bridge")
            _ip("-n", self.switch, "link", "set", "br0", "up")
            for name in self._initial:
                self.add_host(name)
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, kind: object, value: object, tb: object) -> None:
        problems = self.close()
        if problems and kind is None:
            raise NetLabError("; ".join(problems))

    def __getitem__(self, name: str) -> Host:
        return self.hosts[name]

    def add_host(self, name: str) -> Host:
        """A new host on the bridge with the next address (10.77.0.<count + 1>)."""
        if not self._open:
            raise NetLabError("add_host() outside the lab's `with` block")
        if not _NAME.match(name) or name in self.hosts:
            raise NetLabError(f"bad or duplicate host name {name!r} (a-z, 0-9, -; 16 at most)")
        if len(self.hosts) >= 254:
            raise NetLabError(f"a lab has at most 254 hosts ({SUBNET}.0/24)")
        host = Host(self, name, len(self.hosts) + 1)
        self.hosts[name] = host
        self._write_hosts_file()
        host._create()
        return host

    def _write_hosts_file(self) -> None:
        lines = ["127.0.0.1 localhost", "::1 localhost ip6-localhost ip6-loopback"]
        lines += [f"{h.address} {h.host_id} {h.name}" for h in self.hosts.values()]
        with open(self.hosts_file, "w") as f:  # truncates in place: mounted copies see it
            f.write("\n".join(lines) + "\n")

    @property
    def key_file(self) -> Path:
        """The ln_daemon key of the lab (one key for every host, as in a real setup)."""
        if self._key_file is None:
            from links_and_nodes.manager.processes.daemon_keys import create_key_file

            self._key_file = self.directory / "daemon.key"
            create_key_file(self._key_file)
        return self._key_file

    def close(self) -> list[str]:
        """Stop the daemons (SIGTERM, then SIGKILL), kill whatever else runs in the lab and
        delete its namespaces.  Idempotent; returns what could not be cleaned up."""
        if not self._open:
            return []
        self._open = False
        problems = []
        for daemon in self.daemons:
            with contextlib.suppress(Exception):
                daemon.terminate(timeout=10.0)
        for proc in self.processes:
            if proc.poll() is None:
                proc.kill()
        netnss = [h.netns for h in self.hosts.values()] + [self.switch]
        for netns in netnss:
            _kill_namespace(netns)
        for proc in self.processes + [h.anchor for h in self.hosts.values() if h.anchor]:
            try:
                proc.wait(WAIT)
            except subprocess.TimeoutExpired:
                problems.append(f"pid {proc.pid} survived SIGKILL")
        left = sorted(set(netnss) & set(namespaces()))
        if left:
            problems.append(f"namespaces left behind: {', '.join(left)}")
        return problems


def require_netlab() -> None:
    """In a test: skip, saying why, if no lab can be built here; under CI=1 (which runs as
    root) fail instead, like the project's other tests that need something of the machine."""
    import pytest

    reason = netlab_available()
    if reason is None:
        return
    text = f"network namespaces unavailable: {reason}"
    if os.environ.get("CI"):
        pytest.fail(f"{text} (CI=1: this is a failure)")
    pytest.skip(text)
