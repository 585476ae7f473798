"""How the web UI is asked for: `webui`, `webui_port` and `webui_auth_file` in the instance
section (errors at file:line:col), `--webui`/`--webui-port`/`--webui-host`,
LNM_WEBUI_AUTH_FILE over the section's file, and the refusals at start: no auth file on a
non-loopback address, an auth file others may read."""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

import pytest

from links_and_nodes.manager.config import ConfigError, load
from links_and_nodes.manager.frontends.webui import WebUIError, plan
from links_and_nodes.manager.frontends.webui.auth import hash_password

LIMIT = 60.0


def _lnc(tmp_path: Path, extra: str) -> Path:
    path = tmp_path / "x.lnc"
    path.write_text(f"instance\nname: webui_test\nmanager: :12345\n{extra}\n")
    return path


def test_instance_keys(tmp_path: Path) -> None:
    inst = load(_lnc(tmp_path, "webui: on\nwebui_port: 8080\nwebui_auth_file: users")).instance
    assert (inst.webui, inst.webui_port, inst.webui_auth_file) == \
        (True, 8080, str(tmp_path / "users"))
    inst = load(_lnc(tmp_path, "webui: off")).instance
    assert (inst.webui, inst.webui_port) == (False, None)


@pytest.mark.parametrize(("line", "error"), [
    ("webui: maybe", r"x\.lnc:4:8: webui must be on or off, not 'maybe'"),
    ("webui_port: 70000", r"x\.lnc:4:13: webui_port must be a TCP port 0\.\.65535"),
    ("webui_port: -1", r"x\.lnc:4:13: webui_port must be a TCP port"),
])
def test_instance_key_errors(tmp_path: Path, line: str, error: str) -> None:
    with pytest.raises(ConfigError, match=error):
        load(_lnc(tmp_path, line))


def _args(*argv: str) -> argparse.Namespace:
    from links_and_nodes.manager.frontends.cli import build_parser

    return build_parser().parse_args(["--port", "1", "--instance", "x", *argv])


def test_plan(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("LNM_WEBUI_AUTH_FILE", raising=False)
    assert plan(_args(), None) is None
    p = plan(_args("--webui"), None)
    assert p is not None and (p.port, p.host, p.auth_file) == (None, "127.0.0.1", None)
    p = plan(_args("--webui-port", "0"), None)
    assert p is not None and (p.port, p.host) == (0, "127.0.0.1")
    config = load(_lnc(tmp_path, "webui_port: 8080\nwebui_auth_file: users"))
    # off loopback without TLS only with --webui-insecure (test_tls.py)
    p = plan(_args("--host", "0.0.0.0", "--webui-insecure"), config)
    assert p is not None and (p.port, p.host, p.auth_file) == (8080, "0.0.0.0",
                                                                str(tmp_path / "users"))
    monkeypatch.setenv("LNM_WEBUI_AUTH_FILE", "/elsewhere/users")  # the environment wins
    assert plan(_args(), config).auth_file == "/elsewhere/users"  # type: ignore[union-attr]
    monkeypatch.delenv("LNM_WEBUI_AUTH_FILE")
    with pytest.raises(WebUIError, match="loopback only, but the manager's address is "
                                         "0.0.0.0"):
        plan(_args("--webui", "--host", "0.0.0.0"), None)
    with pytest.raises(WebUIError, match="--webui-host is 192.0.2.1"):
        plan(_args("--webui-port", "0", "--webui-host", "192.0.2.1"), None)


def _manager(*argv: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "links_and_nodes.manager", "--port", "0",
                           "--instance", f"webui_refused_{os.getpid()}", *argv],
                          capture_output=True, text=True, timeout=LIMIT,
                          env={**os.environ, **(env or {})}, stdin=subprocess.DEVNULL)


def test_manager_refuses_to_start(tmp_path: Path) -> None:
    run = _manager("--webui", "--host", "0.0.0.0")
    assert run.returncode == 2 and "loopback only" in run.stderr and not run.stdout
    users = tmp_path / "users"
    users.write_text(f"alice {hash_password('pw', n=1 << 10)}\n")
    users.chmod(0o644)
    run = _manager("--webui", env={"LNM_WEBUI_AUTH_FILE": str(users)})
    assert run.returncode == 2 and "group or other may access it" in run.stderr
    assert not run.stdout
