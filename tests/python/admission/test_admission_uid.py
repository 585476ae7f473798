"""Admission by peer credentials (docs/security.md, "Client admission to the manager"):
with `client_uids`/`client_gids`, a loopback client is admitted only if the user owning
its end of the connection (as the kernel lists it) is named, or is in a named group;
everyone else gets LN_EPERM with the user and the lists in the text, and the manager logs
it.  Clients of another user are run with setpriv, which needs root."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys

import pytest

from admission.clients import Client
from admission.conftest import WAIT, Admission
from admission.test_admission_key import LnPermError
from links_and_nodes.manager.registry.admission import _diag_uid, _proc_uid, peer_uid

OTHER = 65534  # nobody / nogroup

# A client as another user: prints "admitted" or the exception libln's binding raised.
_PROBE = """
import sys
sys.path.insert(0, sys.argv[2])
from admission.clients import Client
try:
    Client(sys.argv[1], "other").close()
    print("admitted")
except Exception as exc:
    print(type(exc).__name__, exc)
"""


def _as_other_user(address: str) -> str:
    if os.geteuid() != 0 or shutil.which("setpriv") is None:
        pytest.skip("running a client as another user needs root and setpriv")
    tests = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    run = subprocess.run(["setpriv", f"--reuid={OTHER}", f"--regid={OTHER}", "--clear-groups",
                          sys.executable, "-c", _PROBE, address, tests],
                         capture_output=True, text=True, timeout=WAIT, cwd="/",
                         env={**os.environ, "HOME": "/nonexistent"})
    assert run.returncode == 0, run.stderr
    return run.stdout.strip()


def test_user_outside_client_uids_is_refused(admission: Admission) -> None:
    manager = admission.start("client_uids: 0")
    out = _as_other_user(f"127.0.0.1:{manager.port}")
    assert out.startswith("LnPermError "), out
    assert f"user {OTHER}" in out
    assert f"is not admitted by instance {admission.instance} (client_uids: 0)" in out
    manager.wait_log(rf"handshake refused: user {OTHER}\b.* is not admitted by instance")


def test_user_in_a_listed_group_is_admitted(admission: Admission) -> None:
    manager = admission.start(f"client_uids: 0\nclient_gids: {OTHER}")
    assert _as_other_user(f"127.0.0.1:{manager.port}") == "admitted"
    manager.wait_log(rf"client other \(127\.0\.0\.1:\d+\): connected .*\), admitted by user {OTHER}")


def test_listed_user_is_admitted_without_key(admission: Admission) -> None:
    manager = admission.start(f"client_uids: {os.geteuid()}")
    with Client(f"127.0.0.1:{manager.port}", "listed") as client:
        client.publish("adm.listed")


def test_other_local_user_needs_the_key_when_there_is_one(admission: Admission) -> None:
    key = admission.tmp / "instance.key"
    key.write_text("ab" * 32 + "\n")
    key.chmod(0o600)
    manager = admission.start(f"client_key_file: {key}")
    out = _as_other_user(f"127.0.0.1:{manager.port}")
    assert out.startswith("LnPermError "), out
    assert "admits client 'other' only with its client key" in out


def test_remote_client_is_refused_by_lists_without_key(admission: Admission,
                                                       remote_host: str) -> None:
    manager = admission.start("client_uids: 0", host="0.0.0.0")
    with pytest.raises(LnPermError) as info:
        Client(f"{remote_host}:{manager.port}", "faraway")
    assert (f"a client from a remote host is not admitted by instance {admission.instance} "
            "(client_uids: 0; no client_key_file admits others)") in str(info.value)


def test_both_kernel_lookups_find_the_user() -> None:
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen(1)
        with socket.create_connection(server.getsockname()) as _client:
            conn, _ = server.accept()
            with conn:
                local, peer = conn.getsockname(), conn.getpeername()
                assert _diag_uid(local, peer) == os.geteuid()
                assert _proc_uid(local, peer) == os.geteuid()
                assert peer_uid(local, peer) == os.geteuid()
                assert _diag_uid(local, (peer[0], peer[1] ^ 1)) is None  # no such socket
