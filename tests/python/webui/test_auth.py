"""The web UI's auth file, password hashes, sessions and `ln_manager webui-passwd`
(python/links_and_nodes/manager/frontends/webui/auth.py)."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest

from links_and_nodes.manager.frontends.webui.auth import (
    AuthFileError,
    Sessions,
    basic_credentials,
    csrf_ok,
    hash_password,
    load_auth_file,
    verify_password,
)


def test_hash_verifies_only_its_password() -> None:
    stored = hash_password("s3cret pass", n=1 << 10)
    assert stored.startswith("scrypt$1024$8$1$")
    assert verify_password("s3cret pass", stored)
    assert not verify_password("s3cret pas", stored)
    assert not verify_password("", stored)
    assert hash_password("x", n=1 << 10) != hash_password("x", n=1 << 10)  # salted


@pytest.mark.parametrize("stored", ["", "plain", "scrypt$1024$8$1$!!$AA", "md5$x$y$z$a$b",
                                    "scrypt$3$8$1$AAAA$AAAA", "scrypt$1024$8$1$AAAA$"])
def test_malformed_hash_never_verifies(stored: str) -> None:
    assert not verify_password("", stored)
    assert not verify_password("x", stored)


def _auth_file(tmp_path: Path, text: str, mode: int = 0o600) -> Path:
    path = tmp_path / "users"
    path.write_text(text)
    path.chmod(mode)
    return path


def test_auth_file_readable_by_others_is_refused(tmp_path: Path) -> None:
    line = f"alice {hash_password('pw', n=1 << 10)}\n"
    for mode in (0o640, 0o604, 0o660, 0o644):
        path = _auth_file(tmp_path, line, mode)
        with pytest.raises(AuthFileError, match=r"group or other may access it .*chmod 600"):
            load_auth_file(path)
    assert list(load_auth_file(_auth_file(tmp_path, line, 0o600))) == ["alice"]
    assert list(load_auth_file(_auth_file(tmp_path, line, 0o400))) == ["alice"]


def test_auth_file_errors_name_the_line(tmp_path: Path) -> None:
    path = _auth_file(tmp_path, f"# users\nalice {hash_password('pw', n=1 << 10)}\nbob pw\n")
    with pytest.raises(AuthFileError, match=r"users:3: expected 'USER scrypt"):
        load_auth_file(path)
    with pytest.raises(AuthFileError, match="no users"):
        load_auth_file(_auth_file(tmp_path, "# nobody\n"))
    with pytest.raises(AuthFileError, match="No such file"):
        load_auth_file(tmp_path / "missing")


def test_sessions_login_expiry_and_cookie() -> None:
    sessions = Sessions({"alice": hash_password("pw", n=1 << 10)}, lifetime=3600)
    assert sessions.login("alice", "wrong") is None
    assert sessions.login("mallory", "pw") is None
    session = sessions.login("alice", "pw")
    assert session is not None and session.user == "alice"
    assert sessions.get(session.token) is session
    assert sessions.get("forged") is None and sessions.get(None) is None
    cookie = sessions.cookie(session)
    assert cookie.startswith(f"lnm_session={session.token};")
    for flag in ("HttpOnly", "SameSite=Strict", "Path=/", "Max-Age=3600"):
        assert flag in cookie.split("; ")
    assert csrf_ok(session, session.csrf)
    assert not csrf_ok(session, session.csrf[:-1]) and not csrf_ok(session, None)
    assert session.csrf != session.token
    session.expires = time.monotonic() - 1
    assert sessions.get(session.token) is None


def test_basic_credentials() -> None:
    assert basic_credentials("Basic YWxpY2U6cDpx") == ("alice", "p:q")
    assert basic_credentials("Bearer x") is None
    assert basic_credentials("Basic !!!") is None
    assert basic_credentials("Basic YWxpY2U=") is None  # no colon


def test_webui_passwd_prints_a_line_that_verifies(tmp_path: Path) -> None:
    run = subprocess.run([sys.executable, "-m", "links_and_nodes.manager", "webui-passwd",
                          "alice"], input="correct horse\n", capture_output=True, text=True,
                         timeout=60, check=True)
    path = _auth_file(tmp_path, run.stdout)
    users = load_auth_file(path)
    assert verify_password("correct horse", users["alice"])
    bad = subprocess.run([sys.executable, "-m", "links_and_nodes.manager", "webui-passwd"],
                         input="", capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2 and "usage" in bad.stderr
    empty = subprocess.run([sys.executable, "-m", "links_and_nodes.manager", "webui-passwd",
                            "bob"], input="\n", capture_output=True, text=True, timeout=60)
    assert empty.returncode == 1 and "empty password" in empty.stderr
