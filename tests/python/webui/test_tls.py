"""The web UI over TLS without a browser: the certificate and key checked at start (a
missing, malformed, encrypted, world-readable or mismatched file named in the error), the
options (command line over the instance section, both files or neither, a port of its own,
no plain HTTP on a non-loopback address without --webui-insecure), and a served HTTPS port:
Secure cookies, HSTS, https:// as the only Origin of the WebSocket (wss), plain HTTP
answered with nothing; the manager's exit status and text for each refusal."""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import ssl
import subprocess
import sys
import urllib.error
import urllib.request
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest
from process_management.conftest import Lab, lab  # noqa: F401 - fixture

from links_and_nodes.manager.config import load
from links_and_nodes.manager.frontends.control import Control
from links_and_nodes.manager.frontends.webui import WebUI, WebUIError, plan
from links_and_nodes.manager.frontends.webui.auth import hash_password
from links_and_nodes.manager.frontends.webui.tls import HSTS, TLSError, server_context
from links_and_nodes.manager.registry.server import listen_socket

from .certs import Cert, self_signed
from .test_server import LIMIT, _basic, _need_websockets, request

try:
    import websockets
    from websockets.asyncio.client import connect
except ImportError:  # pragma: no cover - requirements-dev.txt
    websockets = None  # type: ignore[assignment]


# ---- the certificate and key ------------------------------------------------------------
def test_server_context_names_the_file_at_fault(tmp_path: Path) -> None:
    good, other = self_signed(tmp_path / "a"), self_signed(tmp_path / "b")
    cert, key = str(good.cert), str(good.key)
    context = server_context(cert, key)
    assert context.minimum_version == ssl.TLSVersion.TLSv1_2
    not_pem = tmp_path / "cert.der"
    not_pem.write_bytes(b"\x30\x82\x01\x00garbage\xff")
    broken = tmp_path / "broken.crt"
    broken.write_text("-----BEGIN CERTIFICATE-----\nAAAA\n-----END CERTIFICATE-----\n")
    encrypted = tmp_path / "encrypted.key"
    subprocess.run(["openssl", "pkey", "-in", key, "-aes256", "-passout", "pass:x", "-out",
                    str(encrypted)], check=True, timeout=LIMIT)
    encrypted.chmod(0o600)
    shared = tmp_path / "shared.key"
    shared.write_bytes(good.key.read_bytes())
    shared.chmod(0o644)
    missing = tmp_path / "nowhere.crt"
    cases = [
        ((str(missing), key), f"web UI TLS certificate {missing}: No such file or directory"),
        ((cert, str(tmp_path)), f"web UI TLS key {tmp_path}: Is a directory"),
        ((str(not_pem), key), f"web UI TLS certificate {not_pem}: not a PEM file"),
        ((key, key), f"web UI TLS certificate {key}: no '-----BEGIN CERTIFICATE-----' block"),
        ((cert, cert), f"web UI TLS key {cert}: no '-----BEGIN ... PRIVATE KEY-----' block"),
        ((str(broken), key), f"web UI TLS certificate {broken}: not a valid PEM certificate"),
        ((cert, str(other.key)), f"web UI TLS key {other.key} does not belong to the "
                                 f"certificate {cert}"),
        ((cert, str(encrypted)), f"web UI TLS key {encrypted}: encrypted with a passphrase"),
        ((cert, str(shared)), f"web UI TLS key {shared}: other users may access it (mode "
                              f"0644); refused: run 'chmod o-rwx {shared}'"),
    ]
    for (c, k), text in cases:
        with pytest.raises(TLSError) as err:
            server_context(c, k)
        assert str(err.value).startswith(text), (c, k, str(err.value))


# ---- the options --------------------------------------------------------------------------
def _args(*argv: str) -> argparse.Namespace:
    from links_and_nodes.manager.frontends.cli import build_parser

    return build_parser().parse_args(["--port", "1", "--instance", "x", *argv])


def test_plan_tls_options(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("LNM_WEBUI_AUTH_FILE", str(tmp_path / "users"))
    lnc = tmp_path / "x.lnc"
    lnc.write_text("instance\nname: webui_tls\nmanager: :12345\nwebui_port: 0\n"
                   "webui_tls_cert: ui.crt\nwebui_tls_key: /etc/ui.key\n")
    config = load(lnc)
    p = plan(_args("--host", "0.0.0.0"), config)
    assert p is not None and (p.host, p.tls_cert, p.tls_key, p.scheme, p.warning) == \
        ("0.0.0.0", str(tmp_path / "ui.crt"), "/etc/ui.key", "https", None)
    p = plan(_args("--webui-tls-key", "/k.pem"), config)  # the command line wins, each alone
    assert p is not None and (p.tls_cert, p.tls_key) == (str(tmp_path / "ui.crt"), "/k.pem")
    p = plan(_args("--webui-port", "0", "--webui-tls-cert", "rel.crt", "--webui-tls-key",
                   "/k.pem"), None)
    assert p is not None and p.tls_cert == os.path.abspath("rel.crt")
    with pytest.raises(WebUIError, match=r"the key \(--webui-tls-key, webui_tls_key\) is "
                                         "missing"):
        plan(_args("--webui-port", "0", "--webui-tls-cert", "/c.pem"), None)
    with pytest.raises(WebUIError, match="needs a port of its own"):
        plan(_args("--webui", "--webui-tls-cert", "/c.pem", "--webui-tls-key", "/k.pem"), None)
    with pytest.raises(WebUIError, match="--webui-tls-cert without a web UI"):
        plan(_args("--webui-tls-cert", "/c.pem", "--webui-tls-key", "/k.pem"), None)
    # without TLS: loopback as before; another address refused unless --webui-insecure
    p = plan(_args("--webui-port", "0"), None)
    assert p is not None and (p.host, p.scheme, p.warning) == ("127.0.0.1", "http", None)
    for argv, where in ((("--webui", "--host", "0.0.0.0"), "the manager's address"),
                        (("--webui-port", "0", "--webui-host", "192.0.2.1"), "--webui-host")):
        with pytest.raises(WebUIError) as err:
            plan(_args(*argv), None)
        assert f"({where}) without TLS refused" in str(err.value)
        assert "--webui-tls-cert FILE --webui-tls-key FILE" in str(err.value)
        assert "--webui-insecure" in str(err.value)
        p = plan(_args(*argv, "--webui-insecure"), None)
        assert p is not None and p.scheme == "http" and p.warning is not None
        assert "in the clear" in p.warning


# ---- an HTTPS port ------------------------------------------------------------------------
@pytest.fixture
async def tls_ui(tmp_path: Path) -> AsyncIterator[tuple[int, ssl.SSLContext]]:
    """A web UI with an auth file over TLS; its port and a client context that trusts its
    certificate (and checks the name 127.0.0.1 against it)."""
    cert: Cert = self_signed(tmp_path / "tls")
    control = Control(None, None)  # type: ignore[arg-type]
    ui = WebUI(control, {"alice": hash_password("right", n=1 << 10)},
               tls=server_context(str(cert.cert), str(cert.key)))
    sock = listen_socket("127.0.0.1", 0)
    await ui.listen(sock)
    try:
        yield sock.getsockname()[1], ssl.create_default_context(cafile=str(cert.cert))
    finally:
        await ui.close()


async def test_https_secure_cookie_and_hsts(tls_ui: tuple[int, ssl.SSLContext]) -> None:
    port, client = tls_ui
    login = await request(port, "POST", "/login", {"Authorization": _basic("alice", "right")},
                          tls=client, host=f"robot.test:{port}")
    assert login.status == 204
    assert {"Secure", "HttpOnly", "SameSite=Strict", "Path=/"} <= \
        set(login.headers["set-cookie"].split("; "))
    assert login.headers["strict-transport-security"] == HSTS == "max-age=31536000"
    cookie = login.headers["set-cookie"].split(";")[0]
    page = await request(port, "GET", "/", {"Cookie": cookie}, tls=client,
                         host=f"robot.test:{port}")
    assert page.status == 200 and page.headers["strict-transport-security"] == HSTS
    refused = await request(port, "GET", "/api/session", tls=client, host=f"robot.test:{port}")
    assert refused.status == 401 and "strict-transport-security" in refused.headers
    # a loopback name gets none: a browser would hold every port of it to HTTPS
    local = await request(port, "GET", "/", {"Cookie": cookie}, tls=client)
    assert local.status == 200 and "strict-transport-security" not in local.headers
    csrf = json.loads((await request(port, "GET", "/api/session", {"Cookie": cookie},
                                     tls=client)).body)["csrf"]
    out = await request(port, "POST", "/logout", {"Cookie": cookie, "X-CSRF-Token": csrf},
                        tls=client)
    assert out.status == 204 and {"Max-Age=0", "Secure"} <= \
        set(out.headers["set-cookie"].split("; "))


async def test_plain_http_to_the_tls_port_gets_no_answer(
        tls_ui: tuple[int, ssl.SSLContext]) -> None:
    port, client = tls_ui
    reader, writer = await asyncio.open_connection("127.0.0.1", port)
    writer.write(f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n\r\n".encode())
    try:
        data = await asyncio.wait_for(reader.read(), LIMIT)
    except ConnectionResetError:
        data = b""
    writer.close()
    assert b"HTTP/" not in data and b"lnm_session" not in data
    # and the port still serves HTTPS
    assert (await request(port, "GET", "/", tls=client)).status == 401


async def test_wss_takes_https_origin_only(tls_ui: tuple[int, ssl.SSLContext]) -> None:
    _need_websockets()
    port, client = tls_ui
    login = await request(port, "POST", "/login", {"Authorization": _basic("alice", "right")},
                          tls=client)
    cookie = login.headers["set-cookie"].split(";")[0]
    url = f"wss://127.0.0.1:{port}/ws"
    plain: Any = f"http://127.0.0.1:{port}"  # websockets' Origin type
    with pytest.raises(websockets.InvalidStatus) as err:
        await connect(url, ssl=client, origin=plain, additional_headers={"Cookie": cookie},
                      open_timeout=LIMIT)
    assert err.value.response.status_code == 403
    secure: Any = f"https://127.0.0.1:{port}"
    async with connect(url, ssl=client, origin=secure, additional_headers={"Cookie": cookie},
                       open_timeout=LIMIT) as conn:
        await conn.send(json.dumps({"id": 1, "op": "status"}))
        answer = json.loads(await asyncio.wait_for(conn.recv(), LIMIT))
        assert answer["id"] == 1 and answer["ok"] is True


# ---- the manager's start ------------------------------------------------------------------
def _manager(tmp: Path, *argv: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "links_and_nodes.manager", "--port", "0",
                           "--instance", f"webui_tls_{os.getpid()}_{tmp.name}", *argv],
                          capture_output=True, text=True, timeout=LIMIT, cwd=tmp,
                          env={**os.environ, "LN_RUNTIME_DIR": str(tmp / "run")},
                          stdin=subprocess.DEVNULL)


def test_manager_refuses_bad_tls_files_and_plain_http_off_loopback(tmp_path: Path) -> None:
    good, other = self_signed(tmp_path / "a"), self_signed(tmp_path / "b")
    missing = tmp_path / "missing.crt"
    run = _manager(tmp_path, "--webui-port", "0", "--webui-tls-cert", str(missing),
                   "--webui-tls-key", str(good.key))
    assert run.returncode == 1 and not run.stdout
    assert run.stderr == (f"ln_manager: error: web UI TLS certificate {missing}: No such file "
                          "or directory\n")
    run = _manager(tmp_path, "--webui-port", "0", "--webui-tls-cert", "a/webui.crt",
                   "--webui-tls-key", str(other.key))  # relative to the working directory
    assert run.returncode == 1 and not run.stdout
    assert run.stderr == (f"ln_manager: error: web UI TLS key {other.key} does not belong to "
                          f"the certificate {good.cert}\n")
    run = _manager(tmp_path, "--webui", "--webui-tls-cert", str(good.cert),
                   "--webui-tls-key", str(good.key))
    assert run.returncode == 2 and "the web UI over TLS needs a port of its own" in run.stderr


def test_manager_non_loopback_needs_tls_or_insecure(lab: Lab) -> None:  # noqa: F811
    users = lab.tmp / "users"
    users.write_text(f"alice {hash_password('pw', n=1 << 10)}\n")
    users.chmod(0o600)
    lab.env["LNM_WEBUI_AUTH_FILE"] = str(users)
    config = lab.write("")
    argv = ("--no-console", "--webui-port", "0", "--webui-host", "0.0.0.0")
    refused = subprocess.run([sys.executable, "-m", "links_and_nodes.manager", "-c",
                              str(config), *argv], capture_output=True, text=True,
                             env=lab.env, timeout=LIMIT, stdin=subprocess.DEVNULL)
    assert refused.returncode == 2 and not refused.stdout
    assert refused.stderr.startswith("ln_manager: error: web UI on 0.0.0.0 (--webui-host) "
                                     "without TLS refused: its password and session cookie "
                                     "would cross the network in the clear; give "
                                     "--webui-tls-cert FILE --webui-tls-key FILE")
    proc = lab.manager(config, *argv, "--webui-insecure")
    lab.wait_listening(proc)
    assert proc.stdout is not None
    line = proc.stdout.readline().strip()
    assert line.startswith("ln_manager: web UI on http://127.0.0.1:"), (line, lab.log())
    with pytest.raises(urllib.error.HTTPError) as err:  # the login page
        urllib.request.urlopen(line.rsplit(" ", 1)[1], timeout=LIMIT)
    assert err.value.code == 401
    assert "ln_manager: warning: web UI on 0.0.0.0 over plain HTTP (--webui-insecure)" in \
        lab.log()
