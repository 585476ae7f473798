"""The web UI's server over a real socket with the manager's real command table (a Control
without a configuration): the session cookie and its flags, login against an auth file
(wrong password refused), the CSRF token on state-changing commands (HTTP and WebSocket),
the WebSocket's Origin and cookie checks, the Host check without an auth file, static files
without traversal, and the manager's log as a live subscription."""

from __future__ import annotations

import asyncio
import base64
import json
import logging
import re
import ssl
from collections.abc import AsyncIterator
from dataclasses import dataclass
from typing import Any

import pytest
from buildtree import missing_test_tool

from links_and_nodes.manager.frontends.control import Control
from links_and_nodes.manager.frontends.webui import WebUI
from links_and_nodes.manager.frontends.webui.auth import hash_password
from links_and_nodes.manager.registry.server import listen_socket

try:
    import websockets
    from websockets.asyncio.client import connect
except ImportError:  # pragma: no cover - requirements-dev.txt
    websockets = None  # type: ignore[assignment]

LIMIT = 30.0  # seconds for anything to happen, never a measurement


@dataclass
class Answer:
    status: int
    headers: dict[str, str]
    body: bytes


async def request(port: int, method: str, path: str, headers: dict[str, str] | None = None,
                  body: bytes = b"", host: str | None = None,
                  length: int | None = None, tls: ssl.SSLContext | None = None) -> Answer:
    """One request and its answer; over TLS with the client context `tls`."""
    reader, writer = await asyncio.open_connection(
        "127.0.0.1", port, ssl=tls, server_hostname="127.0.0.1" if tls else None)
    lines = [f"{method} {path} HTTP/1.1", f"Host: {host or f'127.0.0.1:{port}'}",
             f"Content-Length: {len(body) if length is None else length}",
             "Connection: close"]
    lines += [f"{k}: {v}" for k, v in (headers or {}).items()]
    writer.write(("\r\n".join(lines) + "\r\n\r\n").encode() + body)
    data = await asyncio.wait_for(reader.read(), LIMIT)
    writer.close()
    head, _, rest = data.partition(b"\r\n\r\n")
    first, *fields = head.decode("latin-1").split("\r\n")
    parsed = {}
    for f in fields:
        k, _, v = f.partition(":")
        parsed[k.strip().lower()] = v.strip()
    return Answer(int(first.split()[1]), parsed, rest)


@dataclass
class Running:
    ui: WebUI
    port: int

    @property
    def origin(self) -> str:
        return f"http://127.0.0.1:{self.port}"


async def _serve(users: dict[str, str] | None) -> AsyncIterator[Running]:
    ui = WebUI(Control(None, None), users)  # type: ignore[arg-type]
    sock = listen_socket("127.0.0.1", 0)
    await ui.listen(sock)
    try:
        yield Running(ui, sock.getsockname()[1])
    finally:
        await ui.close()


@pytest.fixture
async def open_ui() -> AsyncIterator[Running]:
    async for r in _serve(None):
        yield r


@pytest.fixture
async def auth_ui() -> AsyncIterator[Running]:
    async for r in _serve({"alice": hash_password("right", n=1 << 10)}):
        yield r


def _basic(user: str, password: str) -> str:
    return "Basic " + base64.b64encode(f"{user}:{password}".encode()).decode()


async def session_of(port: int, **headers: str) -> tuple[str, str]:
    """(cookie, csrf) from the page."""
    page = await request(port, "GET", "/", headers)
    assert page.status == 200, page
    cookie = page.headers.get("set-cookie", "").split(";")[0] or headers["Cookie"]
    csrf = re.search(rb'name="csrf-token" content="([^"]+)"', page.body)
    assert csrf is not None
    return cookie, csrf.group(1).decode()


# ---- sessions and login -------------------------------------------------------------------
async def test_open_access_cookie_flags_and_csrf_in_page(open_ui: Running) -> None:
    page = await request(open_ui.port, "GET", "/")
    assert page.status == 200
    flags = page.headers["set-cookie"].split("; ")
    assert flags[0].startswith("lnm_session=") and len(flags[0]) > 40
    assert {"HttpOnly", "SameSite=Strict", "Path=/"} <= set(flags)
    assert b'name="csrf-token" content="{{csrf}}"' not in page.body
    assert "default-src 'self'" in page.headers["content-security-policy"]
    cookie, csrf = await session_of(open_ui.port)
    info = await request(open_ui.port, "GET", "/api/session", {"Cookie": cookie})
    assert json.loads(info.body)["csrf"] == csrf


async def test_open_access_answers_loopback_names_only(open_ui: Running) -> None:
    refused = await request(open_ui.port, "GET", "/", host=f"attacker.example:{open_ui.port}")
    assert refused.status == 403 and b"loopback" in refused.body
    assert (await request(open_ui.port, "GET", "/", host=f"localhost:{open_ui.port}")).status \
        == 200


async def test_login_with_the_auth_file(auth_ui: Running) -> None:
    port = auth_ui.port
    page = await request(port, "GET", "/")
    assert page.status == 401 and b'id="login"' in page.body and "set-cookie" not in page.headers
    prompt = await request(port, "GET", "/login")
    assert prompt.status == 401 and prompt.headers["www-authenticate"].startswith("Basic")
    for user, password in (("alice", "wrong"), ("bob", "right"), ("alice", "")):
        bad = await request(port, "POST", "/login", {"Authorization": _basic(user, password)})
        assert bad.status == 401 and "set-cookie" not in bad.headers
    good = await request(port, "POST", "/login", {"Authorization": _basic("alice", "right")})
    assert good.status == 204
    cookie = good.headers["set-cookie"].split(";")[0]
    assert "HttpOnly" in good.headers["set-cookie"]
    assert (await request(port, "GET", "/", {"Cookie": cookie})).status == 200
    assert (await request(port, "GET", "/", {"Cookie": "lnm_session=forged"})).status == 401
    # logging out needs the CSRF token and ends the session
    csrf = re.search(rb'name="csrf-token" content="([^"]+)"',
                     (await request(port, "GET", "/", {"Cookie": cookie})).body)
    assert csrf is not None
    assert (await request(port, "POST", "/logout", {"Cookie": cookie})).status == 403
    out = await request(port, "POST", "/logout", {"Cookie": cookie,
                                                   "X-CSRF-Token": csrf.group(1).decode()})
    assert out.status == 204 and "Max-Age=0" in out.headers["set-cookie"]
    assert (await request(port, "GET", "/", {"Cookie": cookie})).status == 401
    good = await request(port, "POST", "/login", {"Authorization": _basic("alice", "right")})
    cookie = good.headers["set-cookie"].split(";")[0]
    # with an auth file another Host name is fine (the UI may listen on every interface)
    assert (await request(port, "GET", "/", {"Cookie": cookie},
                          host="robot-pc.example")).status == 200


async def test_missing_cookie_refused(auth_ui: Running) -> None:
    for path in ("/api/session", "/nothing"):
        assert (await request(auth_ui.port, "GET", path)).status == 401
    command = await request(auth_ui.port, "POST", "/api/command", body=b'{"op": "status"}')
    assert command.status == 401


# ---- CSRF over HTTP -----------------------------------------------------------------------
async def test_http_command_csrf(open_ui: Running) -> None:
    cookie, csrf = await session_of(open_ui.port)
    look = await request(open_ui.port, "POST", "/api/command", {"Cookie": cookie},
                         b'{"op": "status"}')
    assert look.status == 200 and json.loads(look.body)["ok"] is True
    for headers in ({"Cookie": cookie}, {"Cookie": cookie, "X-CSRF-Token": csrf + "x"}):
        change = await request(open_ui.port, "POST", "/api/command", headers,
                               b'{"op": "start", "target": "all"}')
        assert change.status == 403 and b"CSRF" in change.body
    change = await request(open_ui.port, "POST", "/api/command",
                           {"Cookie": cookie, "X-CSRF-Token": csrf},
                           b'{"op": "start", "target": "all"}')
    assert change.status == 200
    assert "runs no configuration" in json.loads(change.body)["error"]  # got to the handler
    foreign = await request(open_ui.port, "POST", "/api/command",
                            {"Cookie": cookie, "X-CSRF-Token": csrf,
                             "Origin": "http://evil.example"}, b'{"op": "status"}')
    assert foreign.status == 403


# ---- WebSocket ----------------------------------------------------------------------------
def _need_websockets() -> None:
    if websockets is None:
        missing_test_tool("the Python package websockets (requirements-dev.txt)")


async def _ws(ui: Running, cookie: str | None, origin: str | None) -> Any:
    headers = {"Cookie": cookie} if cookie else {}
    return await connect(f"ws://127.0.0.1:{ui.port}/ws", origin=origin,  # type: ignore[arg-type]
                         additional_headers=headers, open_timeout=LIMIT)


async def _ask(conn: Any, message: dict[str, Any]) -> dict[str, Any]:
    await conn.send(json.dumps(message))
    while True:
        answer = json.loads(await asyncio.wait_for(conn.recv(), LIMIT))
        if answer.get("id") == message.get("id"):
            return answer  # type: ignore[no-any-return]


async def test_websocket_refuses_foreign_origin_and_missing_cookie(open_ui: Running) -> None:
    _need_websockets()
    cookie, _ = await session_of(open_ui.port)
    for ck, origin, status in ((cookie, "http://evil.example", 403), (cookie, None, 403),
                               (None, open_ui.origin, 401),
                               ("lnm_session=forged", open_ui.origin, 401),
                               (cookie, f"http://127.0.0.1:{open_ui.port + 1}", 403)):
        with pytest.raises(websockets.InvalidStatus) as err:
            await _ws(open_ui, ck, origin)
        assert err.value.response.status_code == status


async def test_websocket_origin_of_a_tls_proxy(open_ui: Running) -> None:
    """Behind a TLS-terminating proxy that passes the Host on, the page's origin is https."""
    _need_websockets()
    cookie, _ = await session_of(open_ui.port)
    async with await _ws(open_ui, cookie, f"https://127.0.0.1:{open_ui.port}") as conn:
        assert (await _ask(conn, {"id": 1, "op": "status"}))["ok"] is True


async def test_websocket_commands_need_csrf_to_change_state(open_ui: Running) -> None:
    _need_websockets()
    cookie, csrf = await session_of(open_ui.port)
    async with await _ws(open_ui, cookie, open_ui.origin) as conn:
        status = await _ask(conn, {"id": 1, "op": "status"})
        assert status == {"id": 1, "ok": True, "processes": [], "states": []}
        for token in (None, "wrong", ""):
            message = {"id": 2, "op": "start", "target": "all"}
            if token is not None:
                message["csrf"] = token
            refused = await _ask(conn, message)
            assert refused["ok"] is False and refused["code"] == "ECSRF"
        done = await _ask(conn, {"id": 3, "op": "start", "target": "all", "csrf": csrf})
        assert done["ok"] is False and "runs no configuration" in done["error"]
        unknown = await _ask(conn, {"id": 4, "op": "no_such_op"})
        assert unknown["code"] == "ECSRF"  # unknown ops count as changing
        unknown = await _ask(conn, {"id": 5, "op": "no_such_op", "csrf": csrf})
        assert "unknown command" in unknown["error"]
        bad = await _ask(conn, {"id": 6, "op": "subscribe_output", "name": "x"})
        assert bad["ok"] is False and "runs no configuration" in bad["error"]


async def test_websocket_log_subscription(open_ui: Running) -> None:
    _need_websockets()
    cookie, csrf = await session_of(open_ui.port)
    async with await _ws(open_ui, cookie, open_ui.origin) as conn:
        sub = await _ask(conn, {"id": 1, "op": "subscribe_log", "csrf": csrf})
        assert sub["ok"] and isinstance(sub["sub"], int)
        logging.getLogger("ln_manager").warning("web UI test message 4711")
        while True:
            event = json.loads(await asyncio.wait_for(conn.recv(), LIMIT))
            if event.get("event") == "log" and "4711" in event["text"]:
                break
        assert event["level"] == "warning" and event["sub"] == sub["sub"]
        # worker threads log too: their records come through the loop
        await asyncio.to_thread(logging.getLogger("ln_manager").error, "from a thread 4712")
        while True:
            event = json.loads(await asyncio.wait_for(conn.recv(), LIMIT))
            if event.get("event") == "log" and "4712" in event["text"]:
                break
        assert event["level"] == "error"
        assert (await _ask(conn, {"id": 2, "op": "unsubscribe", "sub": sub["sub"]}))["ok"]
        again = await _ask(conn, {"id": 3, "op": "unsubscribe", "sub": sub["sub"]})
        assert again["ok"] is False


# ---- static files -------------------------------------------------------------------------
@pytest.mark.parametrize("path", ["/static/../webui/auth.py", "/static/%2e%2e/auth.py",
                                  "/static/..%2fauth.py", "/static/.hidden",
                                  "/static/vendor/LICENSE", "/static/vendor/../app.js",
                                  "/static/a/b/c", "/static//etc/passwd", "/static/"])
async def test_no_traversal(open_ui: Running, path: str) -> None:
    assert (await request(open_ui.port, "GET", path)).status == 404


async def test_static_files_served(open_ui: Running) -> None:
    js = await request(open_ui.port, "GET", "/static/app.js")
    assert js.status == 200 and js.headers["content-type"].startswith("text/javascript")
    assert (await request(open_ui.port, "POST", "/static/app.js")).status == 405


async def test_oversized_body_refused_before_reading_it(open_ui: Running) -> None:
    cookie, _ = await session_of(open_ui.port)
    answer = await request(open_ui.port, "POST", "/api/command", {"Cookie": cookie},
                           length=(1 << 20) + 1)
    assert answer.status == 413
