"""Support code of the ln_daemon tests: a private daemon per test (free port, own key file,
own log), a raw framed connection for the protocol tests, /proc helpers to prove that no
process of a tree survives, and waiting for events with a generous upper bound only."""

from __future__ import annotations

import asyncio
import os
import selectors
import signal
import socket
import struct
import subprocess
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from polling import free_port, wait_for  # noqa: F401  (the daemon tests import them from here)

from links_and_nodes.manager.processes import daemon_client as dc
from links_and_nodes.manager.processes import daemon_keys as dk
from links_and_nodes.manager.processes import daemon_wire as dw
from links_and_nodes.wire import codec as wc

REPO = Path(__file__).resolve().parents[3]
DAEMON = REPO / "build" / "release" / "ln_daemon" / "ln_daemon"
WAIT = 30.0  # seconds; only ever an upper bound while waiting for something to happen
PATH_ENV = {"PATH": "/usr/local/bin:/usr/bin:/bin"}


def unique_instance() -> str:
    return f"t{os.getpid()}_{uuid.uuid4().hex[:8]}"


def daemon_exe() -> str:
    exe = os.environ.get("LN_DAEMON") or str(DAEMON)
    if not os.access(exe, os.X_OK):
        pytest.fail(f"{exe} is missing: run scons first")
    return exe


# ---- /proc -----------------------------------------------------------------------------------


def proc_stat(pid: int) -> tuple[str, int, int, int, int] | None:
    """(state, ppid, pgrp, session, start time) of a process, None if it is gone."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except (FileNotFoundError, ProcessLookupError):
        return None
    fields = text[text.rindex(")") + 2:].split()
    return fields[0], int(fields[1]), int(fields[2]), int(fields[3]), int(fields[19])


def alive(pid: int, start_time: int | None = None) -> bool:
    """True if `pid` runs (not a zombie) and, when given, has this start time (so a reused
    pid does not count)."""
    st = proc_stat(pid)
    if st is None or st[0] in ("Z", "X"):
        return False
    return start_time is None or st[4] == start_time


def descendants(root: int) -> list[int]:
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            st = proc_stat(int(entry.name))
            if st is not None:
                children.setdefault(st[1], []).append(int(entry.name))
    out, todo = [], [root]
    while todo:
        for child in children.get(todo.pop(), []):
            out.append(child)
            todo.append(child)
    return out




# ---- a private daemon ---------------------------------------------------------------------------


@dataclass
class Daemon:
    proc: subprocess.Popen[bytes]
    port: int
    key: bytes
    key_file: Path
    log: Path
    instance: str
    data_port: int
    extra: list[subprocess.Popen[bytes]] = field(default_factory=list)

    async def connect(self, instance: str | None = None, *, key: bytes | None = None,
                      state_events: bool = False) -> dc.DaemonClient:
        return await dc.DaemonClient.connect("127.0.0.1", self.port, key or self.key,
                                             instance or self.instance,
                                             state_events=state_events)

    def log_text(self) -> str:
        return self.log.read_text(errors="replace")


def start_daemon(tmp: Path, *args: str, user: int | None = None, group: int | None = None,
                 env: dict[str, str] | None = None, key_file: Path | None = None) -> Daemon:
    """ln_daemon --port 0 --foreground with a fresh key file in `tmp` (or `key_file`, to
    share one key between daemons as an installation does); returns once it listens (its
    ready line says on which ports).  With `user`, the daemon runs as that user (and
    `group`), who then owns the key file.  `env` is added to the daemon's environment."""
    name = f"daemon-{uuid.uuid4().hex[:6]}"
    if key_file is None:
        key_file = tmp / f"{name}.key"
        key = dk.create_key_file(key_file)
    else:
        key = dk.read_key_file(key_file)
    log = tmp / f"{name}.log"
    as_user: dict[str, object] = {}
    if user is not None:
        os.chown(key_file, user, group if group is not None else -1)
        as_user = {"user": user, "group": group, "extra_groups": []}
    proc = subprocess.Popen([daemon_exe(), "--port", "0", "--bind", "127.0.0.1", "--key-file",
                             str(key_file), "--log", str(log), "--foreground", *args],
                            stdout=subprocess.PIPE, stdin=subprocess.DEVNULL,
                            env={**os.environ, **(env or {})},
                            **as_user)  # type: ignore[call-overload]
    assert proc.stdout is not None
    sel = selectors.DefaultSelector()
    sel.register(proc.stdout, selectors.EVENT_READ)
    if not sel.select(WAIT):
        proc.kill()
        pytest.fail("ln_daemon printed no ready line")
    line = proc.stdout.readline().decode()
    sel.close()
    if " listening on " not in line:
        proc.wait()
        pytest.fail(f"ln_daemon did not start: {line!r}")
    port = int(line.split(" listening on ", 1)[1].split()[0].rsplit(":", 1)[1])
    data_port = int(line.rsplit(" data port ", 1)[1])
    return Daemon(proc, port, key, key_file, log, unique_instance(), data_port)


def stop_daemon(daemon: Daemon) -> list[str]:
    """SIGTERM as in production: the daemon stops every process and exits 0.  Whatever is
    left after that is killed and reported as a problem."""
    problems = []
    tree = descendants(daemon.proc.pid)
    if daemon.proc.poll() is None:
        daemon.proc.send_signal(signal.SIGTERM)
        try:
            code = daemon.proc.wait(WAIT)
            if code != 0:
                problems.append(f"ln_daemon exited with {code}")
        except subprocess.TimeoutExpired:
            problems.append("ln_daemon ignored SIGTERM")
            daemon.proc.kill()
            daemon.proc.wait()
    left = [pid for pid in tree if alive(pid)]
    for pid in left:
        with _suppress_lookup():
            os.kill(pid, signal.SIGKILL)
    if left:
        problems.append(f"processes outlived the daemon: {left}")
    if daemon.proc.stdout is not None:
        daemon.proc.stdout.close()
    for extra in daemon.extra:
        if extra.poll() is None:
            extra.kill()
        extra.wait()
    return problems


class _suppress_lookup:
    def __enter__(self) -> None:
        return None

    def __exit__(self, kind: object, value: object, tb: object) -> bool:
        return kind is ProcessLookupError


# ---- events -------------------------------------------------------------------------------------


async def next_event(client: dc.DaemonClient, predicate: Callable[[object], bool],
                     what: str, seen: list[object] | None = None) -> object:
    """The next event that matches; the events before it go to `seen`."""
    queue = client.events()
    deadline = asyncio.get_running_loop().time() + WAIT
    while True:
        remaining = deadline - asyncio.get_running_loop().time()
        try:
            event = await asyncio.wait_for(queue.get(), max(remaining, 0.001))
        except TimeoutError:
            pytest.fail(f"gave up waiting for {what}")
        if event is None:
            pytest.fail(f"connection ended while waiting for {what}")
        if predicate(event):
            return event
        if seen is not None:
            seen.append(event)


async def exited(client: dc.DaemonClient, name: str,
                 lines: list[str] | None = None) -> dw.Exited:
    """Wait for the Exited event of `name`; its output lines before it go to `lines`."""
    seen: list[object] = []
    event = await next_event(client, lambda e: isinstance(e, dw.Exited) and e.name == name,
                             f"exit of {name}", seen)
    if lines is not None:
        lines += [e.text for e in seen if isinstance(e, dw.OutputLine) and e.name == name]
    assert isinstance(event, dw.Exited)
    return event


async def line(client: dc.DaemonClient, name: str, text: str) -> dw.OutputLine:
    event = await next_event(client, lambda e: isinstance(e, dw.OutputLine)
                             and e.name == name and e.text == text, f"line {text!r} of {name}")
    assert isinstance(event, dw.OutputLine)
    return event


def spec(name: str, command: str, *, shell: bool = True, **kw: object) -> dw.SpawnSpec:
    return dw.SpawnSpec(name=name, command=command, shell=shell, env=dict(PATH_ENV),
                        **kw)  # type: ignore[arg-type]


# ---- raw protocol -------------------------------------------------------------------------------


class RawConnection:
    """A blocking socket speaking frames by hand, to send what a real client never would."""

    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=WAIT)
        self.keys: dict[str, bytes] | None = None
        self.seq_out = 0
        self.seq_in = 0

    def close(self) -> None:
        self.sock.close()

    def read_exact(self, n: int) -> bytes:
        data = b""
        while len(data) < n:
            chunk = self.sock.recv(n - len(data))
            if not chunk:
                raise EOFError(f"connection closed after {len(data)} of {n} bytes")
            data += chunk
        return data

    def read_frame(self) -> tuple[int, int, bytes]:
        (length,) = struct.unpack("<I", self.read_exact(4))
        body = self.read_exact(length)
        if self.keys is not None:
            body, tag = body[:-dw.TAG_BYTES], body[-dw.TAG_BYTES:]
            assert tag == dw.frame_tag(self.keys["to_client"], self.seq_in, body)
            self.seq_in += 1
        mtype, req = struct.unpack_from("<BI", body)
        return mtype, req, body[5:]

    def frame(self, mtype: int, req: int, payload: bytes, *, tagged: bool | None = None,
              seq: int | None = None) -> bytes:
        body = struct.pack("<BI", mtype, req) + payload
        if tagged if tagged is not None else self.keys is not None:
            assert self.keys is not None
            use = self.seq_out if seq is None else seq
            if seq is None:
                self.seq_out += 1
            body += dw.frame_tag(self.keys["to_daemon"], use, body)
        return struct.pack("<I", len(body)) + body

    def send(self, data: bytes) -> None:
        self.sock.sendall(data)

    def hello(self) -> bytes:
        """Reads DAEMON_HELLO; returns the daemon's nonce."""
        mtype, _, payload = self.read_frame()
        assert mtype == dw.Msg.DAEMON_HELLO and payload[:8] == dw.MAGIC
        return payload[10:]

    def client_hello(self, key: bytes, instance: str, daemon_nonce: bytes) -> bytes:
        nonce = os.urandom(32)
        keys = dw.proofs(key, daemon_nonce, nonce, instance.encode())
        payload = dw.MAGIC + struct.pack("<H", dw.PROTOCOL_VERSION) + nonce \
            + wc.encode_str(instance) + keys["client"]
        self._pending_keys = keys
        return self.frame(dw.Msg.CLIENT_HELLO, 0, payload, tagged=False)

    def authenticate(self, key: bytes, instance: str) -> None:
        self.send(self.client_hello(key, instance, self.hello()))
        mtype, _, payload = self.read_frame()
        assert mtype == dw.Msg.AUTH_OK, payload
        self.keys = self._pending_keys

    def expect_error_and_close(self) -> tuple[int, str]:
        """Reads frames up to an ERROR, then insists the daemon closes the connection."""
        while True:
            mtype, _, payload = self.read_frame()
            if mtype == dw.Msg.ERROR:
                break
        code, text = dw.decode_error(payload)
        self.sock.settimeout(WAIT)
        rest = b""
        while True:
            chunk = self.sock.recv(65536)
            if not chunk:
                break
            rest += chunk
        return int(code), text


