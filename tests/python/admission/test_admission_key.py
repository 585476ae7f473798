"""Admission by key (docs/security.md, "Client admission to the manager"): with the
instance's `client_key_file`, a client that reaches the manager from off loopback is
admitted only if it proves the key, and the manager must prove it back; a client without
the key, with a wrong one or with an unusable key file gets LN_EPERM with a text saying
why, and the manager logs the refusal.  Loopback clients of the manager's own user need no
key."""

from __future__ import annotations

import socket
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from admission.clients import Client
from admission.conftest import Admission, write_key
from links_and_nodes._libln import ERRORS_BY_CODE
from links_and_nodes.manager.frontends.listing import ListingError, fetch
from links_and_nodes.tools import protocol as p
from links_and_nodes.tools.commands import ManagerError
from links_and_nodes.tools.scripting import Manager as ScriptManager

LnPermError = next(cls for cls in ERRORS_BY_CODE.values() if cls.name == "EPERM")


def _keyed(admission: Admission, tmp_path: Path) -> tuple[str, Path]:
    """A manager on every interface with a client key; the key file's path."""
    key = write_key(tmp_path / "instance.key")
    manager = admission.start(f"client_key_file: {key}", host="0.0.0.0")
    return str(manager.port), key


def test_remote_client_without_key_is_refused(admission: Admission, tmp_path: Path,
                                              remote_host: str) -> None:
    port, _ = _keyed(admission, tmp_path)
    with pytest.raises(LnPermError) as info:
        Client(f"{remote_host}:{port}", "nokey")
    text = str(info.value)
    assert "refused client \"nokey\"" in text
    assert f"instance {admission.instance} admits client 'nokey' only with its client key" \
        in text
    assert "LN_CLIENT_KEY_FILE" in text
    admission.managers[0].wait_log(r"closing: handshake refused: instance \S+ admits client "
                                   r"'nokey' only with its client key")


def test_remote_client_with_wrong_key_is_refused(admission: Admission, tmp_path: Path,
                                                 remote_host: str,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    port, _ = _keyed(admission, tmp_path)
    monkeypatch.setenv("LN_CLIENT_KEY_FILE", str(write_key(tmp_path / "other.key")))
    with pytest.raises(LnPermError) as info:
        Client(f"{remote_host}:{port}", "wrongkey")
    assert "client 'wrongkey' proved a wrong client key" in str(info.value)
    admission.managers[0].wait_log(r"handshake refused: client 'wrongkey' proved a wrong "
                                   r"client key")


def test_remote_client_with_the_key_is_admitted_and_publishes(
        admission: Admission, tmp_path: Path, remote_host: str,
        monkeypatch: pytest.MonkeyPatch) -> None:
    port, key = _keyed(admission, tmp_path)
    copy = write_key(tmp_path / "home-copy.key", bytes.fromhex(key.read_text().strip()))
    monkeypatch.setenv("LN_CLIENT_KEY_FILE", str(copy))
    with Client(f"{remote_host}:{port}", "keyed") as client:
        client.publish("adm.keyed")
        client.subscribe("adm.keyed")
    admission.managers[0].wait_log(r"client keyed \(\S+\): connected .*\), admitted by key$")


def test_default_key_file_is_used(admission: Admission, tmp_path: Path, remote_host: str) -> None:
    port, key = _keyed(admission, tmp_path)
    home_key = tmp_path / "home" / ".config" / "links_and_nodes" / "client.key"
    home_key.parent.mkdir(parents=True)
    write_key(home_key, bytes.fromhex(key.read_text().strip()))
    with Client(f"{remote_host}:{port}", "homekey") as client:
        client.publish("adm.home")


def test_unusable_key_file_is_named(admission: Admission, tmp_path: Path, remote_host: str,
                                    monkeypatch: pytest.MonkeyPatch) -> None:
    port, key = _keyed(admission, tmp_path)
    shared = write_key(tmp_path / "shared.key", bytes.fromhex(key.read_text().strip()),
                       mode=0o644)
    monkeypatch.setenv("LN_CLIENT_KEY_FILE", str(shared))
    with pytest.raises(LnPermError) as info:
        Client(f"{remote_host}:{port}", "loosekey")
    assert f"client key file '{shared}' is accessible by group or others (mode 0644)" \
        in str(info.value)


def test_loopback_client_of_the_same_user_needs_no_key(admission: Admission,
                                                       tmp_path: Path) -> None:
    port, _ = _keyed(admission, tmp_path)
    with Client(f"127.0.0.1:{port}", "local") as client:
        client.publish("adm.local")
    admission.managers[0].wait_log(r"client local \(127\.0\.0\.1:\d+\): connected .*"
                                   r"admitted by user \d+")


def _fake_manager(server: socket.socket, instance: str, proves: bool) -> None:
    """Challenges one client, then answers AUTH with a proof made without the key (`proves`)
    or with no proof at all, and welcomes it."""
    conn, _ = server.accept()
    with conn:
        conn.recv(4096)  # HELLO
        conn.sendall(p.encode(p.Challenge(instance, "11" * 32)))
        conn.recv(4096)  # AUTH
        if proves:
            conn.sendall(p.encode(p.AuthOk("22" * 32)))
        conn.sendall(p.encode(p.Welcome(p.VERSION, 1, "victim", instance)))
        conn.recv(4096)  # until the client closes


@contextmanager
def _impostor(proves: bool) -> Iterator[int]:
    """A fake manager of instance "impostor" on a free local port (yielded) for one client:
    it answers a proof with an AUTH_OK made without the key (`proves`) or with none."""
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen(1)
        fake = threading.Thread(target=_fake_manager, args=(server, "impostor", proves),
                                daemon=True)
        fake.start()
        try:
            yield server.getsockname()[1]
        finally:
            fake.join(30)


@pytest.mark.parametrize(("proves", "text"), [
    (True, "failed to prove the client key of instance \"impostor\""),
    (False, "did not prove the client key of instance \"impostor\""),
])
def test_client_refuses_a_manager_that_cannot_prove_the_key(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, proves: bool, text: str) -> None:
    monkeypatch.setenv("LN_CLIENT_KEY_FILE", str(write_key(tmp_path / "client.key")))
    with _impostor(proves) as port, pytest.raises(LnPermError) as info:
        Client(f"127.0.0.1:{port}", "victim")
    assert text in str(info.value)


def test_python_tools_refuse_a_manager_that_skips_its_proof(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("LN_CLIENT_KEY_FILE", str(write_key(tmp_path / "client.key")))
    with (_impostor(False) as port,
          pytest.raises(ListingError, match="did not prove the client key")):
        fetch("127.0.0.1", port)


def test_python_tools_prove_the_key_too(admission: Admission, tmp_path: Path, remote_host: str,
                                        monkeypatch: pytest.MonkeyPatch) -> None:
    port, key = _keyed(admission, tmp_path)
    with pytest.raises(ManagerError, match="only with its client key"):
        ScriptManager(f"{remote_host}:{port}")
    monkeypatch.setenv("LN_CLIENT_KEY_FILE", str(key))  # the manager's own copy: same user
    with ScriptManager(f"{remote_host}:{port}") as manager:
        assert manager.instance == admission.instance
    admission.managers[0].wait_log(r"client ln_script \(\S+\): connected .*\), admitted by key$")


def test_ln_services_proves_the_key_too(admission: Admission, tmp_path: Path, remote_host: str,
                                        monkeypatch: pytest.MonkeyPatch) -> None:
    port, key = _keyed(admission, tmp_path)
    with pytest.raises(ListingError, match="only with its client key"):
        fetch(remote_host, int(port))
    monkeypatch.setenv("LN_CLIENT_KEY_FILE", str(key))
    assert fetch(remote_host, int(port)).request_id == 1
    admission.managers[0].wait_log(r"client ln_services \(\S+\): connected .*\), admitted by "
                                   r"key$")
