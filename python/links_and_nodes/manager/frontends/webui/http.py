"""The small HTTP/1.1 side of the web UI: reading one request within size limits and a
timeout (request line, headers, a Content-Length body; no chunked bodies) and writing
one response.  Everything refused is an HttpError carrying the status to answer."""

from __future__ import annotations

import asyncio
from dataclasses import dataclass, field
from urllib.parse import parse_qs, unquote, urlsplit

MAX_LINE = 8192  # bytes of the request line and of one header line
MAX_HEADERS = 64
MAX_HEADER_BYTES = 32768
MAX_BODY = 1 << 20
HEADER_TIMEOUT = 10.0  # seconds for the whole head of a request
BODY_TIMEOUT = 30.0
METHODS = ("GET", "HEAD", "POST")

REASONS = {200: "OK", 204: "No Content", 303: "See Other", 400: "Bad Request",
           401: "Unauthorized", 403: "Forbidden", 404: "Not Found",
           405: "Method Not Allowed", 408: "Request Timeout", 411: "Length Required",
           413: "Content Too Large", 414: "URI Too Long",
           431: "Request Header Fields Too Large", 501: "Not Implemented",
           101: "Switching Protocols", 503: "Service Unavailable"}


class HttpError(Exception):
    def __init__(self, status: int, text: str) -> None:
        super().__init__(text)
        self.status = status


@dataclass
class Request:
    method: str
    target: str
    version: str
    headers: dict[str, str] = field(default_factory=dict)  # lower-case names
    body: bytes = b""

    @property
    def path(self) -> str:
        return unquote(urlsplit(self.target).path)

    @property
    def query(self) -> dict[str, list[str]]:
        return parse_qs(urlsplit(self.target).query)

    def header(self, name: str) -> str:
        return self.headers.get(name.lower(), "")

    @property
    def keep_alive(self) -> bool:
        conn = self.header("connection").lower()
        if self.version == "HTTP/1.0":
            return "keep-alive" in conn
        return "close" not in conn

    def cookies(self) -> dict[str, str]:
        out: dict[str, str] = {}
        for part in self.header("cookie").split(";"):
            name, sep, value = part.strip().partition("=")
            if sep:
                out.setdefault(name, value)
        return out


async def _line(reader: asyncio.StreamReader, status: int) -> bytes:
    try:
        line = await reader.readuntil(b"\n")
    except asyncio.LimitOverrunError:
        raise HttpError(status, "line too long") from None
    except asyncio.IncompleteReadError as exc:
        if not exc.partial:
            raise EOFError from None
        raise HttpError(400, "connection closed within a line") from None
    if len(line) > MAX_LINE:
        raise HttpError(status, "line too long")
    return line.rstrip(b"\r\n")


async def read_request(reader: asyncio.StreamReader, first: bytes = b"") -> Request:
    """The next request; `first` are bytes already read from its start.  EOFError at a
    clean end of the connection, HttpError for a request to refuse."""
    try:
        return await asyncio.wait_for(_head(reader, first), HEADER_TIMEOUT)
    except TimeoutError:
        raise HttpError(408, "request head not complete in time") from None


async def _head(reader: asyncio.StreamReader, first: bytes) -> Request:
    line = first + await _line(reader, 414) if first else await _line(reader, 414)
    if len(line) > MAX_LINE:
        raise HttpError(414, "request line too long")
    try:
        method, target, version = line.decode("ascii").split(" ")
    except (UnicodeDecodeError, ValueError):
        raise HttpError(400, "malformed request line") from None
    if version not in ("HTTP/1.1", "HTTP/1.0"):
        raise HttpError(400, f"unsupported version {version!r}")
    if method not in METHODS:
        raise HttpError(405, f"method {method!r} not allowed")
    if not target.startswith("/"):
        raise HttpError(400, "request target must be a path")
    request = Request(method, target, version)
    total = count = 0
    while True:
        try:
            raw = await _line(reader, 431)
        except EOFError:
            raise HttpError(400, "connection closed within the request head") from None
        if not raw:
            break
        total += len(raw)
        count += 1
        if total > MAX_HEADER_BYTES or count > MAX_HEADERS:
            raise HttpError(431, "request headers too large")
        try:
            name, sep, value = raw.decode("latin-1").partition(":")
        except UnicodeDecodeError:
            raise HttpError(400, "malformed header") from None
        if not sep or not name or name != name.strip() or " " in name:
            raise HttpError(400, "malformed header")
        key = name.lower()
        if key in request.headers and key in ("content-length", "host", "authorization"):
            raise HttpError(400, f"repeated header {name}")
        request.headers[key] = value.strip()
    if request.version == "HTTP/1.1" and "host" not in request.headers:
        raise HttpError(400, "no Host header")
    if "transfer-encoding" in request.headers:
        raise HttpError(501, "chunked request bodies are not supported")
    return request


async def read_body(reader: asyncio.StreamReader, request: Request,
                    limit: int = MAX_BODY) -> None:
    length_text = request.header("content-length") or "0"
    if not length_text.isdigit():
        raise HttpError(400, "bad Content-Length")
    length = int(length_text)
    if length > limit:
        raise HttpError(413, f"body of {length} bytes, at most {limit}")
    if length:
        try:
            request.body = await asyncio.wait_for(reader.readexactly(length), BODY_TIMEOUT)
        except TimeoutError:
            raise HttpError(408, "body not complete in time") from None
        except asyncio.IncompleteReadError:
            raise HttpError(400, "connection closed within the body") from None


def response(status: int, body: bytes = b"", content_type: str = "text/plain; charset=utf-8",
             headers: dict[str, str] | None = None, *, head: bool = False,
             keep_alive: bool = True) -> bytes:
    lines = [f"HTTP/1.1 {status} {REASONS.get(status, 'Status')}",
             f"Content-Length: {len(body)}", "X-Content-Type-Options: nosniff",
             "X-Frame-Options: DENY", "Referrer-Policy: no-referrer",
             "Cache-Control: no-store"]
    if body or status not in (204, 303):
        lines.append(f"Content-Type: {content_type}")
    if not keep_alive:
        lines.append("Connection: close")
    for name, value in (headers or {}).items():
        lines.append(f"{name}: {value}")
    out = ("\r\n".join(lines) + "\r\n\r\n").encode("latin-1")
    return out if head else out + body
