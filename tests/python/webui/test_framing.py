"""The web UI's HTTP request reading (limits, timeouts, malformed requests) and WebSocket
framing (masked, fragmented, control frames between fragments, oversized, unmasked and
binary frames refused), fed through asyncio streams."""

from __future__ import annotations

import asyncio
import os

import pytest

from links_and_nodes.manager.frontends.webui import http as h
from links_and_nodes.manager.frontends.webui import websocket as ws


def _reader(data: bytes, eof: bool = True) -> asyncio.StreamReader:
    reader = asyncio.StreamReader()
    reader.feed_data(data)
    if eof:
        reader.feed_eof()
    return reader


class _Writer:
    def __init__(self) -> None:
        self.data = b""

    def write(self, data: bytes) -> None:
        self.data += data


# ---- HTTP ---------------------------------------------------------------------------------
async def test_request_parsed() -> None:
    req = await h.read_request(_reader(b"GET /static/app.js?x=1 HTTP/1.1\r\nHost: a:1\r\n"
                                       b"Cookie: lnm_session=abc; other=1\r\n\r\n"))
    assert (req.method, req.path, req.query, req.header("HOST")) == \
        ("GET", "/static/app.js", {"x": ["1"]}, "a:1")
    assert req.cookies() == {"lnm_session": "abc", "other": "1"} and req.keep_alive


async def test_request_from_first_bytes() -> None:
    req = await h.read_request(_reader(b" / HTTP/1.1\r\nHost: a\r\n\r\n"), b"GET")
    assert req.method == "GET" and req.path == "/"


@pytest.mark.parametrize(("data", "status"), [
    (b"GET / HTTP/1.1\r\n\r\n", 400),  # no Host
    (b"BREW / HTTP/1.1\r\nHost: a\r\n\r\n", 405),
    (b"GET / HTTP/2\r\nHost: a\r\n\r\n", 400),
    (b"GET http://x/ HTTP/1.1\r\nHost: a\r\n\r\n", 400),
    (b"GET /" + b"a" * 9000 + b" HTTP/1.1\r\nHost: a\r\n\r\n", 414),
    (b"GET / HTTP/1.1\r\nHost: a\r\n" + b"X-A: b\r\n" * 70 + b"\r\n", 431),
    (b"GET / HTTP/1.1\r\nHost: a\r\nX: " + b"b" * 9000 + b"\r\n\r\n", 431),
    (b"GET / HTTP/1.1\r\nHost: a\r\nbad header\r\n\r\n", 400),
    (b"GET / HTTP/1.1\r\nHost: a\r\nHost: b\r\n\r\n", 400),
    (b"POST / HTTP/1.1\r\nHost: a\r\nTransfer-Encoding: chunked\r\n\r\n", 501),
    (b"GET / HTTP/1.1\r\nHost: a\r\n", 400),  # closed within the head
])
async def test_request_refused(data: bytes, status: int) -> None:
    with pytest.raises(h.HttpError) as err:
        await h.read_request(_reader(data))
    assert err.value.status == status


async def test_body_limits() -> None:
    req = h.Request("POST", "/", "HTTP/1.1", {"content-length": str(h.MAX_BODY + 1)})
    with pytest.raises(h.HttpError) as err:
        await h.read_body(_reader(b""), req)
    assert err.value.status == 413
    req = h.Request("POST", "/", "HTTP/1.1", {"content-length": "-1"})
    with pytest.raises(h.HttpError):
        await h.read_body(_reader(b""), req)
    req = h.Request("POST", "/", "HTTP/1.1", {"content-length": "5"})
    await h.read_body(_reader(b"12345"), req)
    assert req.body == b"12345"


async def test_slow_head_times_out(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(h, "HEADER_TIMEOUT", 0.05)

    with pytest.raises(h.HttpError) as err:
        await h.read_request(_reader(b"GET / HTTP/1.1\r\nHost: a\r\n", eof=False))
    assert err.value.status == 408


def test_response_headers() -> None:
    out = h.response(200, b"hi", headers={"Set-Cookie": "a=b"})
    head = out.split(b"\r\n\r\n")[0].decode()
    assert head.startswith("HTTP/1.1 200 OK") and "Content-Length: 2" in head
    assert "X-Content-Type-Options: nosniff" in head and "Set-Cookie: a=b" in head
    assert out.endswith(b"\r\n\r\nhi")
    assert h.response(200, b"hi", head=True).endswith(b"\r\n\r\n")


# ---- WebSocket ----------------------------------------------------------------------------
async def _read(data: bytes, limit: int = ws.MAX_MESSAGE) -> tuple[str, bytes]:
    writer = _Writer()
    text = await ws.read_message(_reader(data), writer, limit)  # type: ignore[arg-type]
    return text, writer.data


def _masked(opcode: int, payload: bytes, fin: bool = True, mask: bytes = b"\x9a\x3c\x51\xe7"
            ) -> bytes:
    return ws.frame(opcode, payload, fin, mask=mask)


def test_accept_key_of_rfc_6455() -> None:
    assert ws.accept_key("dGhlIHNhbXBsZSBub25jZQ==") == "s3pPLMBiTxaQ9kYGzzhZRbK+xOo="
    assert ws.valid_key("dGhlIHNhbXBsZSBub25jZQ==") and not ws.valid_key("short")


@pytest.mark.parametrize("size", [0, 5, 125, 126, 65535, 65536, 300000])
async def test_masked_messages_of_every_length_encoding(size: int) -> None:
    payload = ("é" * size)[:size].encode()[:size].decode("utf-8", "ignore")
    text, _ = await _read(_masked(ws.OP_TEXT, payload.encode(), mask=os.urandom(4)))
    assert text == payload


async def test_fragments_with_a_ping_between() -> None:
    data = (_masked(ws.OP_TEXT, b'{"op":', fin=False) + _masked(ws.OP_PING, b"hi")
            + _masked(ws.OP_CONT, b' "status"', fin=False) + _masked(ws.OP_CONT, b"}"))
    text, answered = await _read(data)
    assert text == '{"op": "status"}'
    assert answered == ws.frame(ws.OP_PONG, b"hi")


@pytest.mark.parametrize(("data", "code"), ids=range(13), argvalues=[
    (ws.frame(ws.OP_TEXT, b"unmasked"), ws.CLOSE_PROTOCOL),
    (bytes([0x81 | 0x40]) + _masked(ws.OP_TEXT, b"x")[1:], ws.CLOSE_PROTOCOL),  # RSV1
    (_masked(ws.OP_CONT, b"x"), ws.CLOSE_PROTOCOL),
    (_masked(ws.OP_TEXT, b"a", fin=False) + _masked(ws.OP_TEXT, b"b"), ws.CLOSE_PROTOCOL),
    (_masked(ws.OP_PING, b"x" * 126), ws.CLOSE_PROTOCOL),
    (_masked(ws.OP_PING, b"x", fin=False), ws.CLOSE_PROTOCOL),
    (_masked(0x3, b"x"), ws.CLOSE_PROTOCOL),
    (_masked(ws.OP_BINARY, b"x"), ws.CLOSE_UNSUPPORTED),
    (_masked(ws.OP_TEXT, b"\xff\xfe"), ws.CLOSE_INVALID),
    (_masked(ws.OP_TEXT, b"x" * 101), ws.CLOSE_TOO_BIG),
    (_masked(ws.OP_TEXT, b"x" * 60, fin=False) + _masked(ws.OP_CONT, b"x" * 60),
     ws.CLOSE_TOO_BIG),
    (_masked(ws.OP_TEXT, b"truncated")[:-3], ws.CLOSE_PROTOCOL),
    (_masked(ws.OP_CLOSE, b"\x03\xe8"), ws.CLOSE_NORMAL),
])
async def test_bad_frames_close(data: bytes, code: int) -> None:
    with pytest.raises(ws.WsClosed) as err:
        await _read(data, limit=100)
    assert err.value.code == code


async def test_oversized_length_refused_before_reading_it() -> None:
    head = bytes([0x81, 0x80 | 127]) + (1 << 40).to_bytes(8, "big") + b"mask"
    with pytest.raises(ws.WsClosed) as err:
        await _read(head)
    assert err.value.code == ws.CLOSE_TOO_BIG


def test_a_client_frame_never_starts_like_an_http_request() -> None:
    """The manager's port tells the two apart by the first 4 bytes: a frame's little-endian
    length is at most MAX_LENGTH < 2**24, so its 4th byte is 0; no request line's is."""
    from links_and_nodes.manager.frontends.webui import REQUEST_LINE_STARTS
    from links_and_nodes.tools import protocol as p

    assert p.HEADER_SIZE == 4 and p.MAX_LENGTH < 1 << 24
    assert all(len(start) == 4 and start[3] != 0 for start in REQUEST_LINE_STARTS)
    assert p.MAX_LENGTH.to_bytes(4, "little")[3] == 0
