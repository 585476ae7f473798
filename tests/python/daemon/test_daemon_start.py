"""Starting the daemon: it refuses key files that are not private, not ours or not a key
(clear message, exit status 1); key file helpers; ensure_local_daemon starts a detached
daemon in its own session once, and reuses it afterwards."""

from __future__ import annotations

import asyncio
import contextlib
import os
import re
import signal
import socket
import stat
import subprocess
from pathlib import Path

import pytest
from daemonproc import DAEMON, WAIT, alive, daemon_exe, free_port, wait_for
from polling import free_daemon_port

from links_and_nodes.manager.processes import daemon_client as dc
from links_and_nodes.manager.processes import daemon_keys as dk
from links_and_nodes.manager.processes import daemon_launch as dl
from links_and_nodes.manager.processes import daemon_wire as dw

HEX = "ab" * 32


def run_daemon(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([daemon_exe(), "--port", "0", "--bind", "127.0.0.1", *args],
                          capture_output=True, text=True, timeout=WAIT)


def key_file(tmp_path: Path, text: str, mode: int) -> Path:
    path = tmp_path / f"key-{mode:o}-{len(text)}"
    path.write_text(text)
    path.chmod(mode)
    return path


@pytest.mark.parametrize("mode", [0o644, 0o640, 0o604, 0o660, 0o606, 0o610])
def test_key_file_open_to_others_is_refused(tmp_path: Path, mode: int) -> None:
    path = key_file(tmp_path, HEX, mode)
    result = run_daemon("--key-file", str(path), "--foreground")
    assert result.returncode == 1
    assert result.stderr == (f"ln_daemon: error: key file '{path}' is accessible by group or "
                             f"others (mode {mode:04o}); it must be private: "
                             f"chmod 600 '{path}'\n")
    with pytest.raises(dk.KeyFileError) as e:
        dk.read_key_file(path)
    assert f"(mode {mode:04o})" in str(e.value)


@pytest.mark.parametrize("text", ["", "abc", HEX[:-1], HEX + "0", "zz" + HEX[2:], HEX + "\n\n",
                                  " " + HEX])
def test_key_file_without_a_key_is_refused(tmp_path: Path, text: str) -> None:
    path = key_file(tmp_path, text, 0o600)
    result = run_daemon("--key-file", str(path), "--foreground")
    assert result.returncode == 1
    assert "holds no valid key: it must contain exactly 64 hex digits" in result.stderr
    with pytest.raises(dk.KeyFileError):
        dk.read_key_file(path)


@pytest.mark.skipif(os.geteuid() != 0, reason="only root can give a file to another user")
def test_key_file_of_another_user_is_refused(tmp_path: Path) -> None:
    path = key_file(tmp_path, HEX, 0o600)
    os.chown(path, 65534, 65534)
    result = run_daemon("--key-file", str(path), "--foreground")
    assert result.returncode == 1
    assert "is owned by uid 65534, not by this daemon's uid 0" in result.stderr
    with pytest.raises(dk.KeyFileError):
        dk.read_key_file(path)


def test_usage_errors(tmp_path: Path) -> None:
    result = run_daemon("--foreground")
    assert result.returncode == 2 and "--key-file is required" in result.stderr
    result = run_daemon("--key-file", str(tmp_path / "missing"), "--foreground")
    assert result.returncode == 1
    assert "cannot open key file" in result.stderr
    path = key_file(tmp_path, HEX, 0o600)
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        result = subprocess.run([daemon_exe(), "--port", str(port), "--bind", "127.0.0.1",
                                 "--key-file", str(path), "--foreground"], capture_output=True,
                                text=True, timeout=WAIT)
    assert result.returncode == 1
    assert f"cannot listen on 127.0.0.1:{port}: Address already in use" in result.stderr


@pytest.mark.parametrize(("args", "text"), [
    (["--udp-fragment-size", "255"], "--udp-fragment-size needs a number 256..65000"),
    (["--udp-fragment-size", "65001"], "--udp-fragment-size needs a number 256..65000"),
    (["--udp-fragment-size", "1k"], "--udp-fragment-size needs a number 256..65000"),
    (["--data-port", "65536"], "--data-port needs a number 0..65535"),
    (["--data-port", "-1"], "--data-port needs a number 0..65535"),
    (["--advertise-data-port", "0"], "--advertise-data-port needs a number 1..65535"),
    (["--port", "65535"], "the default data port (--port + 1) would be 65536; give --data-port"),
    (["--port", "4000", "--data-port", "4000"], "--data-port must differ from --port"),
])
def test_data_port_usage_errors(tmp_path: Path, args: list[str], text: str) -> None:
    path = key_file(tmp_path, HEX, 0o600)
    result = run_daemon("--key-file", str(path), "--foreground", *args)
    assert result.returncode == 2
    assert result.stderr.startswith(f"ln_daemon: error: {text}\n")


def test_default_data_port(tmp_path: Path) -> None:
    port = free_daemon_port()
    path = key_file(tmp_path, HEX, 0o600)
    proc = subprocess.Popen([daemon_exe(), "--port", str(port), "--bind", "127.0.0.1",
                             "--key-file", str(path), "--foreground"], stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True)
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert line == (f"ln_daemon: listening on 127.0.0.1:{port} (pid {proc.pid}), "
                        f"data port {port + 1}\n")
    finally:
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(WAIT) == 0
        if proc.stdout is not None:
            proc.stdout.close()


def test_default_data_port_in_use_takes_another(tmp_path: Path) -> None:
    """Only the default data port (--port + 1) gives way: managers learn the real one."""
    port = free_daemon_port()
    path = key_file(tmp_path, HEX, 0o600)
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", port + 1))
        taken.listen()
        proc = subprocess.Popen([daemon_exe(), "--port", str(port), "--bind", "127.0.0.1",
                                 "--key-file", str(path), "--foreground"],
                                stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        try:
            assert proc.stdout is not None
            line = proc.stdout.readline()
            prefix = f"ln_daemon: listening on 127.0.0.1:{port} (pid {proc.pid}), data port "
            assert line.startswith(prefix), line
            assert int(line[len(prefix):]) not in (0, port, port + 1)
        finally:
            proc.send_signal(signal.SIGTERM)
            assert proc.wait(WAIT) == 0
            if proc.stdout is not None:
                proc.stdout.close()


def _pids_with(text: str) -> list[int]:
    pids = []
    for entry in Path("/proc").iterdir():
        try:
            if entry.name.isdigit() and text.encode() in (entry / "cmdline").read_bytes():
                pids.append(int(entry.name))
        except OSError:
            continue
    return pids


@pytest.mark.parametrize("foreground", [True, False])
def test_data_port_in_use(tmp_path: Path, foreground: bool) -> None:
    """Refused with the daemon's error before the launcher exits, also when detaching (the
    data port is opened after the fork), and nothing is left running."""
    path = key_file(tmp_path, HEX, 0o600)
    with contextlib.ExitStack() as stack:
        tcp = stack.enter_context(socket.socket())
        tcp.bind(("127.0.0.1", 0))
        tcp.listen()
        port = tcp.getsockname()[1]
        udp = stack.enter_context(socket.socket(socket.AF_INET, socket.SOCK_DGRAM))
        with contextlib.suppress(OSError):  # the TCP port alone is enough
            udp.bind(("127.0.0.1", port))
        result = subprocess.run([daemon_exe(), "--port", "0", "--bind", "127.0.0.1",
                                 "--key-file", str(path), "--data-port", str(port),
                                 *(["--foreground"] if foreground else [])],
                                capture_output=True, text=True, timeout=WAIT)
    assert result.returncode == 1, result
    assert result.stdout == ""
    assert result.stderr.startswith("ln_daemon: error: ") and str(port) in result.stderr
    assert result.stderr.count("\n") == 1
    wait_for(lambda: not _pids_with(str(path)), "the refused daemon to be gone")


def test_key_file_helpers(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "a" / "b" / "daemon.key"
    key = dk.create_key_file(path)
    assert len(key) == 32 and dk.read_key_file(path) == key
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert stat.S_IMODE(path.parent.stat().st_mode) == 0o700
    assert stat.S_IMODE(path.parent.parent.stat().st_mode) == 0o700
    assert path.read_text() == key.hex() + "\n"
    with pytest.raises(FileExistsError):
        dk.create_key_file(path)  # never overwritten
    monkeypatch.setenv("LN_DAEMON_KEY_FILE", str(path))
    assert dk.default_key_file() == path
    monkeypatch.delenv("LN_DAEMON_KEY_FILE")
    assert dk.default_key_file() == Path.home() / ".config/links_and_nodes/daemon.key"
    monkeypatch.setenv("LN_ARBITER_PORT", "60001")
    assert dk.default_port() == 60001
    monkeypatch.setenv("LN_ARBITER_PORT", "nope")
    with pytest.raises(dw.DaemonError):
        dk.default_port()
    monkeypatch.delenv("LN_ARBITER_PORT")
    assert dk.default_port() == 54376
    monkeypatch.setenv("LN_DAEMON", "/opt/ln/bin/ln_daemon")
    assert dl.daemon_executable() == "/opt/ln/bin/ln_daemon"
    monkeypatch.delenv("LN_DAEMON")
    assert dl.daemon_executable() == str(DAEMON)  # the in-tree release build


def test_ensure_local_daemon(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("LN_DAEMON", daemon_exe())
    key_path = tmp_path / "daemon.key"
    key = dk.create_key_file(key_path)
    log = tmp_path / "daemon.log"
    port = free_port()
    pid = None
    try:
        asyncio.run(dl.ensure_local_daemon(port, key_path, log, data_port=0))
        text = wait_for(lambda: log.exists() and re.search(r"ln_daemon\[(\d+)\]: listening",
                                                           log.read_text()),
                        "the daemon's log line")
        pid = int(text.group(1))  # type: ignore[union-attr]
        assert alive(pid)
        assert os.getsid(pid) == pid  # its own session, detached from ours
        assert os.getpgid(pid) != os.getpgid(0)

        async def use() -> None:
            client = await dc.DaemonClient.connect("127.0.0.1", port, key, "ensure")
            await client.ping()
            assert (await client.net_info()).data_port not in (0, port)
            await client.close()
            # A second call finds it answering and starts nothing.
            await dl.ensure_local_daemon(port, key_path, log)

        asyncio.run(use())
        assert log.read_text().count("listening on") == 1
    finally:
        if pid is not None and alive(pid):
            os.kill(pid, signal.SIGTERM)
            wait_for(lambda: not alive(pid), "the detached daemon to exit")


def test_ensure_local_daemon_reports_start_errors(tmp_path: Path,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("LN_DAEMON", daemon_exe())
    bad = key_file(tmp_path, HEX, 0o644)
    with pytest.raises(dw.DaemonError) as e:
        asyncio.run(dl.ensure_local_daemon(free_port(), bad, timeout=WAIT))
    assert "ln_daemon did not start: ln_daemon: error: key file" in str(e.value)


def test_ensure_local_daemon_refuses_a_foreign_port(tmp_path: Path) -> None:
    async def main() -> None:
        async def other(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
            writer.write(b"SSH-2.0-something else\r\n" * 4)
            await writer.drain()
            writer.close()

        server = await asyncio.start_server(other, "127.0.0.1", 0)
        port = server.sockets[0].getsockname()[1]
        async with server:
            with pytest.raises(dw.DaemonError) as e:
                await dl.ensure_local_daemon(port, tmp_path / "unused.key", timeout=WAIT)
            assert "is in use by something that is not ln_daemon" in str(e.value)

    asyncio.run(main())
