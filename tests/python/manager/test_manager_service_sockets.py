"""The manager's clean-up of service providers' Unix sockets: a provider's
`svc.<pid>.<n>.sock` goes when its service is unregistered or its connection closes
(also by SIGKILL), and at start-up every such socket left in the runtime directory goes.
Files with other names, regular files, symlinks, sockets of other uids and sockets another
service still offers are left alone."""

from __future__ import annotations

import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path

import lnwire
import pytest
from mgrproc import WAIT, Manager, require_manager_library, wait_for

require_manager_library()

Start = Callable[..., Manager]
MD = "robot/move"
HASH = 0x0123456789ABCDEF
SIG = "robot/move_request|robot/move_response"
PID = os.getpid()


@pytest.fixture
def runtime() -> Iterator[Path]:
    """A runtime directory with a short path: sun_path holds at most 107 bytes."""
    path = Path(tempfile.mkdtemp(prefix="lns", dir="/tmp"))
    yield path
    shutil.rmtree(path, ignore_errors=True)


@pytest.fixture
def sockets() -> Iterator[list[socket.socket]]:
    opened: list[socket.socket] = []
    yield opened
    for sock in opened:
        sock.close()


@pytest.fixture
def manager_in_runtime(start_manager: Start, instance: str, runtime: Path) -> Manager:
    return start_manager(instance, "--log-level", "debug", runtime=runtime)


def listen_unix(path: Path, opened: list[socket.socket]) -> Path:
    """A listening AF_UNIX socket at `path`, as a provider makes one."""
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    opened.append(sock)
    sock.bind(str(path))
    sock.listen(1)
    return path


def stale_socket(path: Path) -> Path:
    """A socket file nobody listens on any more, as a killed provider leaves it."""
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as sock:
        sock.bind(str(path))
    return path


def register(client: lnwire.WireClient, name: str, unix_path: Path | str) -> None:
    reply = client.register_service(name, MD, HASH, SIG, unix_path=str(unix_path),
                                    host_id="host-a")
    assert reply.type == lnwire.OK, reply


def test_disconnect_removes_the_providers_sockets(start_manager: Start, instance: str,
                                                  runtime: Path,
                                                  sockets: list[socket.socket]) -> None:
    manager = start_manager(instance, runtime=runtime)
    mine = [listen_unix(runtime / f"svc.{PID}.{n}.sock", sockets) for n in (1, 2)]
    theirs = listen_unix(runtime / f"svc.{PID}.3.sock", sockets)
    with manager.client("user") as user:
        register(user, "theirs", theirs)
        prov = manager.client("prov")
        register(prov, "s1", mine[0])
        register(prov, "s2", mine[1])
        assert all(path.exists() for path in [*mine, theirs])
        prov.close()
        wait_for(lambda: not any(path.exists() for path in mine), "the sockets' removal")
        assert theirs.exists()
        assert user.find_service("theirs", MD, HASH).unix_path == str(theirs)
    for path in mine:
        manager.wait_log(rf"INFO: removed service socket {re.escape(str(path))}$")


def test_unregister_removes_the_socket(start_manager: Start, instance: str, runtime: Path,
                                       sockets: list[socket.socket]) -> None:
    manager = start_manager(instance, runtime=runtime)
    path = listen_unix(runtime / f"svc.{PID}.1.sock", sockets)
    other = listen_unix(runtime / f"svc.{PID}.2.sock", sockets)
    with manager.client("prov") as prov:
        register(prov, "s1", path)
        register(prov, "s2", other)
        assert prov.unregister_service("s1").type == lnwire.OK
        assert not path.exists()  # gone before the answer
        assert other.exists()
        # a replaced registration keeps the old socket: the provider is alive
        register(prov, "s2", path.with_name(f"svc.{PID}.9.sock"))
        assert other.exists()


def test_a_killed_providers_socket_is_removed(manager_in_runtime: Manager,
                                              runtime: Path) -> None:
    manager = manager_in_runtime
    path = runtime / "svc.4242.7.sock"
    script = (
        "import socket, sys, lnwire\n"
        "s = socket.socket(socket.AF_UNIX); s.bind(sys.argv[2]); s.listen(1)\n"
        "c = lnwire.WireClient(int(sys.argv[1])); c.hello('doomed')\n"
        "r = c.register_service('doomed.svc', 'm/d', 1, 'a|b', unix_path=sys.argv[2])\n"
        "print(r.type, flush=True); sys.stdin.read()\n")
    here = Path(__file__).parent
    child = subprocess.Popen([sys.executable, "-c", script, str(manager.port), str(path)],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, cwd=here,
                             env=dict(os.environ, PYTHONPATH=str(here)))
    assert child.stdout is not None and child.stdin is not None
    assert child.stdout.readline().decode().strip() == str(lnwire.OK)
    assert path.exists()
    child.send_signal(signal.SIGKILL)
    child.wait(WAIT)
    child.stdout.close()
    child.stdin.close()
    # the kernel leaves a socket file behind with its process; the manager removes it
    wait_for(lambda: not path.exists(), "the killed provider's socket to be removed")
    manager.wait_log(r"service 'doomed.svc' of client doomed \(.*\) removed")


def test_other_files_are_left(manager_in_runtime: Manager, runtime: Path,
                              sockets: list[socket.socket]) -> None:
    manager = manager_in_runtime
    (runtime / "sub").mkdir()
    regular = runtime / f"svc.{PID}.1.sock"
    regular.write_text("not a socket")
    target = listen_unix(runtime / "sub" / f"svc.{PID}.2.sock", sockets)
    link = runtime / f"svc.{PID}.3.sock"
    link.symlink_to(target)
    paths = {
        "regular": regular,
        "symlink": link,
        "other_name": listen_unix(runtime / "other.sock", sockets),
        "letters": listen_unix(runtime / "svc.x.1.sock", sockets),
        "no_pid": listen_unix(runtime / "svc.1.sock", sockets),
        "suffix": listen_unix(runtime / f"svc.{PID}.4.sock.old", sockets),
    }
    reasons = {"regular": "not a socket", "symlink": "not a socket",
               "other_name": "not named", "letters": "not named", "no_pid": "not named",
               "suffix": "not named"}
    prov = manager.client("prov")
    for name, path in paths.items():
        register(prov, name, path)
    register(prov, "missing", runtime / f"svc.{PID}.5.sock")  # never created
    prov.close()
    manager.wait_log(r"client prov \(.*\): disconnected")
    assert all(path.exists() or path.is_symlink() for path in paths.values())
    assert link.is_symlink() and target.exists()
    for name, path in paths.items():
        manager.wait_log(rf"DEBUG: left service socket {re.escape(str(path))}: "
                         rf"{reasons[name]}")
    manager.wait_log(rf"left service socket {re.escape(str(runtime))}/svc\.{PID}\.5\.sock: "
                     "no such file")
    assert "INFO: removed service socket" not in manager.log()


def test_a_socket_another_service_offers_is_left(manager_in_runtime: Manager, runtime: Path,
                                                 sockets: list[socket.socket]) -> None:
    manager = manager_in_runtime
    shared = listen_unix(runtime / f"svc.{PID}.1.sock", sockets)
    first = manager.client("first")
    second = manager.client("second")
    register(first, "a", shared)
    register(second, "b", shared)
    first.close()
    manager.wait_log(r"client first \(.*\): disconnected")
    assert shared.exists()
    manager.wait_log(r"left service socket .*: another service still offers it")
    second.close()
    wait_for(lambda: not shared.exists(), "the socket's removal with its last service")


@pytest.mark.skipif(os.getuid() != 0, reason="changing a file's owner needs root")
def test_a_socket_of_another_uid_is_left(manager_in_runtime: Manager, runtime: Path,
                                         sockets: list[socket.socket]) -> None:
    manager = manager_in_runtime
    path = listen_unix(runtime / f"svc.{PID}.1.sock", sockets)
    os.chown(path, 65534, 65534, follow_symlinks=False)
    with manager.client("prov") as prov:
        register(prov, "s", path)
        assert prov.unregister_service("s").type == lnwire.OK
        assert path.exists()
    manager.wait_log(r"left service socket .*: owned by uid 65534, not by us \(0\)")


@pytest.mark.parametrize("window", ["0", "0.5"])
def test_startup_removes_stale_sockets_only(start_manager: Start, instance: str,
                                            runtime: Path, sockets: list[socket.socket],
                                            window: str) -> None:
    """With --adopt-window 0 before the ready line, else once the window is over."""
    (runtime / "sub").mkdir()
    stale = [stale_socket(runtime / name) for name in ("svc.1.2.sock", "svc.33.44.sock")]
    live = listen_unix(runtime / "svc.900.5.sock", sockets)  # purged too: nobody knows it
    regular = runtime / "svc.6.7.sock"
    regular.write_text("")
    nested = stale_socket(runtime / "sub" / "svc.8.9.sock")
    link = runtime / "svc.10.11.sock"
    link.symlink_to(nested)
    kept = [regular, nested, stale_socket(runtime / "svc.a.1.sock"),
            stale_socket(runtime / "other.sock"), stale_socket(runtime / "svc.1.2.sock.bak")]
    manager = start_manager(instance, "--adopt-window", window, runtime=runtime)
    if window == "0":
        assert not any(path.exists() for path in [*stale, live])
        manager.wait_log(rf"removed 3 stale service sockets in {re.escape(str(runtime))}: "
                         r"svc\.1\.2\.sock, svc\.33\.44\.sock, svc\.900\.5\.sock$")
    else:
        manager.wait_log(r"adopting 0 topics and [0-9]+ service sockets for 0.5 s")
        manager.wait_log(r"removed 3 service sockets nobody registered again: "
                         r"svc\.1\.2\.sock, svc\.33\.44\.sock, svc\.900\.5\.sock$")
        assert not any(path.exists() for path in [*stale, live])
    assert all(path.exists() for path in kept)
    assert link.is_symlink()
