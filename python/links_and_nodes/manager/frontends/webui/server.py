"""The web UI's HTTP + WebSocket server (docs/webui.md): serves the page, logs users in
(HTTP Basic against the auth file, then a session cookie), checks the Host, the Origin and
the CSRF token, and runs the WebSocket API: JSON commands to the manager's command table
(Control.handle) and the live subscriptions of streams.py.  It runs on its own port or on
the manager's, where server.Server hands it every connection that starts with an HTTP
request line.  With an SSLContext it serves HTTPS (its own port only): Secure cookies,
HSTS, and https:// as the only Origin."""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import ssl
from typing import TYPE_CHECKING, Any

from ....addresses import host_of, is_loopback
from . import assets
from . import http as h
from . import websocket as ws
from .auth import COOKIE, Session, Sessions, basic_credentials, csrf_ok
from .ops import register_ops
from .streams import LogBuffer, Subscriptions, register_streams
from .tls import HSTS

if TYPE_CHECKING:
    from ..control import Control

log = logging.getLogger("ln_manager")

IDLE_TIMEOUT = 60.0  # seconds a kept-alive HTTP connection may wait for its next request
MAX_WS_CLIENTS = 32
QUEUE_LIMIT = 2000  # events queued for one WebSocket client; droppable ones go beyond 200
REQUEST_LINE_STARTS = (b"GET ", b"POST", b"HEAD")
def same_origin(origin: str, host: str, tls: bool = False) -> bool:
    """Whether a request's Origin is the page of this very Host (without TLS also https:,
    behind a TLS proxy that passes the Host on; with TLS only https:)."""
    if tls:
        return bool(host) and origin == f"https://{host}"
    return bool(host) and origin in (f"http://{host}", f"https://{host}")


def _host_name(host_header: str) -> str:
    """The host of a Host header without its port."""
    return host_of(host_header)


class WebUI:
    def __init__(self, control: Control, users: dict[str, str] | None,
                 tls: ssl.SSLContext | None = None) -> None:
        self.control = control
        self.tls = tls
        self.sessions = Sessions(users, secure=tls is not None)
        self.log = LogBuffer(asyncio.get_running_loop())
        logging.getLogger("ln_manager").addHandler(self.log)
        register_ops()
        register_streams()
        # op -> whether it changes state (needs the CSRF token); unknown ops count as such
        self.changing = {c["name"]: bool(c["changes_state"]) for c in control.describe()}
        self._clients = 0
        self._server: asyncio.base_events.Server | None = None
        self._tasks: set[asyncio.Task[Any]] = set()

    # ---- listening --------------------------------------------------------------------
    async def listen(self, sock: Any) -> None:
        extra: dict[str, Any] = {}
        if self.tls is not None:  # a handshake gets as long as a request's head
            extra = {"ssl": self.tls, "ssl_handshake_timeout": h.HEADER_TIMEOUT}
        self._server = await asyncio.start_server(
            lambda r, w: self.serve(r, w, b""), sock=sock, **extra)

    async def close(self) -> None:
        logging.getLogger("ln_manager").removeHandler(self.log)
        if self._server is not None:
            self._server.close()
        for task in list(self._tasks):
            task.cancel()
        if self._tasks:
            await asyncio.gather(*self._tasks, return_exceptions=True)

    # ---- HTTP ------------------------------------------------------------------------------
    @staticmethod
    def takes(first: bytes) -> bool:
        """Whether a connection to the manager's port whose first bytes are `first` (a
        client frame's header size) is an HTTP one, for this web UI."""
        return first in REQUEST_LINE_STARTS

    async def serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter,
                    first: bytes) -> None:
        """One connection; `first`: its bytes already read (by the manager's port)."""
        task = asyncio.current_task()
        if task is not None:
            self._tasks.add(task)
        try:
            while True:
                try:
                    if not first:  # idle between requests: up to IDLE_TIMEOUT
                        first = await asyncio.wait_for(reader.read(1), IDLE_TIMEOUT)
                        if not first:
                            return
                    request = await h.read_request(reader, first)
                except (EOFError, TimeoutError):
                    return
                except h.HttpError as exc:
                    writer.write(h.response(exc.status, str(exc).encode() + b"\n",
                                            keep_alive=False))
                    await writer.drain()
                    return
                first = b""
                if not await self._request(request, reader, writer):
                    return
        except (ConnectionError, ssl.SSLError, asyncio.CancelledError):
            pass
        except Exception:  # a bug of ours must not take the manager down
            log.exception("web UI: internal error")
        finally:
            if task is not None:
                self._tasks.discard(task)
            writer.close()

    async def _request(self, req: h.Request, reader: asyncio.StreamReader,
                       writer: asyncio.StreamWriter) -> bool:
        """Answer one request; False when the connection is to end."""
        try:
            if req.method == "POST":
                await h.read_body(reader, req)
            elif req.header("content-length") not in ("", "0"):
                raise h.HttpError(400, "a body with GET or HEAD")
            self._check_host(req)
            if req.path == "/ws" and req.header("upgrade").lower() == "websocket":
                await self._websocket(req, reader, writer)
                return False
            status, body, ctype, headers = await self._route(req)
        except h.HttpError as exc:
            status, body, ctype, headers = exc.status, str(exc).encode() + b"\n", \
                "text/plain; charset=utf-8", {}
            if exc.status == 401 and req.path == "/login" and req.method != "POST":
                # the browser's own prompt; the page's form (POST) shows its own error
                headers = {"WWW-Authenticate": 'Basic realm="ln_manager", charset="UTF-8"'}
        if self.tls is not None and not is_loopback(_host_name(req.header("host"))):
            # not for loopback names: a browser would hold every port of `localhost` to
            # HTTPS for a year (and ignores it for IP addresses anyway)
            headers = {**headers, "Strict-Transport-Security": HSTS}
        keep = req.keep_alive and status < 400
        writer.write(h.response(status, body, ctype, headers, head=req.method == "HEAD",
                                keep_alive=keep))
        await writer.drain()
        return keep

    def _check_host(self, req: h.Request) -> None:
        """Without an auth file only loopback Host names (no DNS rebinding); a present
        Origin must be this very host."""
        host = req.header("host")
        if self.sessions.open_access and not is_loopback(_host_name(host)):
            raise h.HttpError(403, f"host {host!r} refused: without an auth file the web UI "
                                   "answers loopback names only")
        origin = req.header("origin")
        if origin and not same_origin(origin, host, self.tls is not None):
            raise h.HttpError(403, f"origin {origin!r} refused")

    def _session(self, req: h.Request) -> Session | None:
        return self.sessions.get(req.cookies().get(COOKIE))

    async def _route(self, req: h.Request) -> tuple[int, bytes, str, dict[str, str]]:
        path = req.path
        if path.startswith("/static/"):
            if req.method == "POST":
                raise h.HttpError(405, "static files are read only")
            file = assets.find(path)
            if file is None:
                raise h.HttpError(404, "no such file")
            return 200, file.read_bytes(), assets.content_type(file), {}
        if path == "/login":
            return self._login(req)
        if path in ("/", "/index.html"):
            return self._index(req)
        session = self._session(req)
        if session is None:
            raise h.HttpError(401, "no session: log in at /")
        if path == "/api/session" and req.method != "POST":
            return _json({"user": session.user, "csrf": session.csrf})
        if path == "/api/command" and req.method == "POST":
            return _json(await self._command_http(req, session))
        if path == "/logout" and req.method == "POST":
            if not csrf_ok(session, req.header("x-csrf-token")):
                raise h.HttpError(403, "CSRF token missing or wrong")
            self.sessions.close(session.token)
            return 204, b"", "", {"Set-Cookie": self.sessions.cleared_cookie()}
        raise h.HttpError(404, "not found")

    def _login(self, req: h.Request) -> tuple[int, bytes, str, dict[str, str]]:
        if self.sessions.open_access:
            session = self.sessions.open("local")
        else:
            creds = basic_credentials(req.header("authorization"))
            session = self.sessions.login(*creds) if creds else None
            if session is None:
                if creds:
                    log.warning("web UI: failed login for user %r", creds[0])
                raise h.HttpError(401, "wrong user or password")
            log.info("web UI: user %r logged in", session.user)
        headers = {"Set-Cookie": self.sessions.cookie(session)}
        if req.method == "POST":
            return 204, b"", "", headers
        return 303, b"", "", {**headers, "Location": "/"}

    def _index(self, req: h.Request) -> tuple[int, bytes, str, dict[str, str]]:
        session = self._session(req)
        headers: dict[str, str] = {}
        if session is None and self.sessions.open_access:
            session = self.sessions.open("local")
            headers["Set-Cookie"] = self.sessions.cookie(session)
        if session is None:
            page = (assets.STATIC / "login.html").read_bytes()
            return 401, page, "text/html; charset=utf-8", {}
        page = (assets.STATIC / "index.html").read_text(encoding="utf-8")
        page = page.replace("{{csrf}}", session.csrf).replace("{{user}}", _html(session.user))
        page = page.replace("{{login}}", "none" if self.sessions.open_access else "password")
        headers["Content-Security-Policy"] = ("default-src 'self'; img-src 'self' data: blob:;"
                                              " style-src 'self' 'unsafe-inline'")
        return 200, page.encode(), "text/html; charset=utf-8", headers

    # ---- commands ----------------------------------------------------------------------------
    def changes_state(self, op: str) -> bool:
        return self.changing.get(op, True)

    async def _command_http(self, req: h.Request, session: Session) -> dict[str, Any]:
        try:
            command = json.loads(req.body)
        except (ValueError, RecursionError):
            raise h.HttpError(400, "body is not JSON") from None
        if not isinstance(command, dict) or not isinstance(command.get("op"), str):
            raise h.HttpError(400, 'a command is a JSON object with a string "op"')
        if self.changes_state(command["op"]) and not csrf_ok(
                session, req.header("x-csrf-token")):
            raise h.HttpError(403, "CSRF token missing or wrong (header X-CSRF-Token)")
        return await self._run(command, None)

    async def _run(self, command: dict[str, Any], subs: Subscriptions | None) -> dict[str, Any]:
        from ....tools.commands import ControlError

        command = {k: v for k, v in command.items() if k not in ("csrf", "id")}
        try:
            return await self.control.handle(command, session=subs)
        except ControlError as exc:
            result = {"ok": False, "error": str(exc)}
            if exc.code:
                result["code"] = exc.code
            return result

    # ---- WebSocket ---------------------------------------------------------------------------
    async def _websocket(self, req: h.Request, reader: asyncio.StreamReader,
                         writer: asyncio.StreamWriter) -> None:
        session = self._session(req)
        if session is None:
            raise h.HttpError(401, "no session: log in at /")
        origin, host = req.header("origin"), req.header("host")
        if not same_origin(origin, host, self.tls is not None):
            scheme = "https" if self.tls is not None else "http"
            raise h.HttpError(403, f"origin {origin!r} refused (expected {scheme}://{host})")
        key = req.header("sec-websocket-key")
        if req.header("sec-websocket-version") != "13" or not ws.valid_key(key):
            raise h.HttpError(400, "not a WebSocket version 13 handshake")
        if self._clients >= MAX_WS_CLIENTS:
            raise h.HttpError(503, "too many WebSocket clients")
        writer.write(("HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\n"
                      "Connection: Upgrade\r\n"
                      f"Sec-WebSocket-Accept: {ws.accept_key(key)}\r\n\r\n").encode())
        self._clients += 1
        queue: asyncio.Queue[dict[str, Any] | None] = asyncio.Queue()

        def send(event: dict[str, Any], droppable: bool) -> None:
            if queue.qsize() >= (200 if droppable else QUEUE_LIMIT):
                return
            queue.put_nowait(event)

        subs = Subscriptions(self.control, self.log, send)
        pump = asyncio.get_running_loop().create_task(self._pump(queue, writer))
        pending: set[asyncio.Task[Any]] = set()
        code = ws.CLOSE_NORMAL
        try:
            while not pump.done():
                try:
                    text = await ws.read_message(reader, writer)
                except ws.WsClosed as exc:
                    code = exc.code
                    break
                task = asyncio.get_running_loop().create_task(
                    self._ws_command(text, session, subs, send))
                pending.add(task)
                task.add_done_callback(pending.discard)
        finally:
            subs.close()
            for task in pending:
                task.cancel()
            queue.put_nowait(None)
            with contextlib.suppress(Exception, asyncio.CancelledError):
                await asyncio.wait_for(pump, 2.0)
            with contextlib.suppress(Exception):
                writer.write(ws.close_frame(code))
                await writer.drain()
            self._clients -= 1

    async def _ws_command(self, text: str, session: Session, subs: Subscriptions,
                          send: Any) -> None:
        try:
            command = json.loads(text)
        except (ValueError, RecursionError):
            send({"id": None, "ok": False, "error": "message is not JSON"}, False)
            return
        if not isinstance(command, dict) or not isinstance(command.get("op"), str):
            send({"id": None, "ok": False, "error": 'a message is a JSON object with a '
                                                   'string "op"'}, False)
            return
        ident = command.get("id")
        if self.changes_state(command["op"]) and not csrf_ok(session, command.get("csrf")):
            send({"id": ident, "ok": False, "error": "CSRF token missing or wrong",
                  "code": "ECSRF"}, False)
            return
        result = await self._run(command, subs)
        if "id" in result:  # a result's own "id" (topic_info: the topic's) is "result_id"
            result["result_id"] = result.pop("id")
        send({"id": ident, **result}, False)

    @staticmethod
    async def _pump(queue: asyncio.Queue[dict[str, Any] | None],
                    writer: asyncio.StreamWriter) -> None:
        while True:
            event = await queue.get()
            if event is None:
                return
            batch = [event]
            while not queue.empty() and len(batch) < 64:
                nxt = queue.get_nowait()
                if nxt is None:
                    queue.put_nowait(None)
                    break
                batch.append(nxt)
            for item in batch:
                writer.write(ws.frame(ws.OP_TEXT, _encode(item)))
            await writer.drain()


def _encode(value: Any) -> bytes:
    """Strict JSON (a browser's JSON.parse takes no NaN): non-finite floats as strings."""
    try:
        return json.dumps(value, separators=(",", ":"), allow_nan=False, default=str).encode()
    except ValueError:
        from ....tools.introspection.values import jsonable

        return json.dumps(jsonable(value), separators=(",", ":"), default=str).encode()


def _json(value: dict[str, Any]) -> tuple[int, bytes, str, dict[str, str]]:
    return 200, _encode(value), "application/json", {}


def _html(text: str) -> str:
    return (text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
            .replace('"', "&quot;"))
