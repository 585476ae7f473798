"""Hostile callers on a provider's socket: garbage, a wrong HELLO, malformed and oversized
requests, connections dropped in the middle of a frame.  Each gets an ERROR frame (or is
dropped) and the provider keeps serving well-behaved callers."""

from __future__ import annotations

import json
import socket
import struct
from collections.abc import Iterator
from pathlib import Path

import pytest

from links_and_nodes import md_loader
from links_and_nodes._libln import ln_error_name

from .conftest import LIMIT, REPO, Setup, stop

md_loader.add_message_definition_dir(REPO / "tests" / "fixtures" / "md" / "services")
ECHO_HASH = md_loader.message_class("lntest/echo").LAYOUT_HASH
MAGIC = 0x56534E4C
HELLO, WELCOME, REQUEST, RESPONSE, ERROR = 1, 2, 3, 4, 5


def frame(kind: int, body: bytes) -> bytes:
    return struct.pack("<IH", len(body) + 2, kind) + body


def text(value: str) -> bytes:
    raw = value.encode()
    return struct.pack("<H", len(raw)) + raw


def hello(name: str = "arm.echo", layout_hash: int = ECHO_HASH, version: int = 1) -> bytes:
    return frame(HELLO, struct.pack("<IH", MAGIC, version) + text(name)
                 + struct.pack("<Q", layout_hash))


def echo_payload(caller: int, seq: int, message: bytes) -> bytes:
    """The wire form of an lntest/echo request: fixed fields, then count + bytes of text."""
    return struct.pack("<IIII", caller, seq, 0, len(message)) + message


def request(call_id: int, payload: bytes) -> bytes:
    return frame(REQUEST, struct.pack("<I", call_id) + payload)


def read_exact(sock: socket.socket, n: int) -> bytes | None:
    data = b""
    while len(data) < n:
        chunk = sock.recv(n - len(data))
        if not chunk:
            return None
        data += chunk
    return data


def read_frame(sock: socket.socket) -> tuple[int, bytes] | None:
    header = read_exact(sock, 6)
    if header is None:
        return None
    length, kind = struct.unpack("<IH", header)
    body = read_exact(sock, length - 2)
    assert body is not None, "provider closed the connection inside a frame"
    return kind, body


def error_of(body: bytes) -> tuple[int, str, str]:
    """(call id, error name, text) of an ERROR frame."""
    call_id, code, n = struct.unpack_from("<IiH", body)
    assert len(body) == 10 + n
    return call_id, ln_error_name(code).decode(), body[10:].decode()


@pytest.fixture
def provider(setup: Setup) -> Iterator[Path]:
    """A thread-pool echo provider with a 1,024-byte request limit; yields its socket path."""
    prov = setup.provider("arm.echo", "pool", "2", "1024")
    (path,) = setup.sockets()
    yield path
    still_serves(setup)
    assert stop(prov) == 0


def connect(path: Path) -> socket.socket:
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    sock.settimeout(LIMIT)
    sock.connect(str(path))
    return sock


def greeted(path: Path) -> socket.socket:
    sock = connect(path)
    sock.sendall(hello())
    assert read_frame(sock) == (WELCOME, b"")
    return sock


def still_serves(setup: Setup) -> None:
    proc = setup.run("once", "arm.echo", "fine", "0", str(LIMIT))
    out, err = proc.communicate(timeout=LIMIT)
    assert json.loads(out) == {"rc": "OK", "error": "", "text": "fine"}, err


def test_garbage_instead_of_hello(setup: Setup, provider: Path) -> None:
    with connect(provider) as sock:
        sock.sendall(b"\x08\x00\x00\x00\x63\x00garbage!")
        answer = read_frame(sock)
        assert answer is not None and answer[0] == ERROR
        assert error_of(answer[1])[1] == "EPROTOCOL"
        assert read_frame(sock) is None  # and the connection is closed
    still_serves(setup)


def test_request_before_hello(provider: Path) -> None:
    with connect(provider) as sock:
        sock.sendall(request(1, echo_payload(0, 0, b"x")))
        answer = read_frame(sock)
        assert answer is not None and answer[0] == ERROR
        assert error_of(answer[1])[1:] == ("EPROTOCOL",
                                           'service "arm.echo": expected a HELLO frame')


@pytest.mark.parametrize(("frame_bytes", "code", "words"), [
    (hello(layout_hash=ECHO_HASH ^ 1), "ELAYOUT", ["lntest/echo", "layout"]),
    (hello(name="arm.other"), "ENOTFOUND", ["arm.echo", "arm.other"]),
    (hello(version=9), "EVERSION", ["protocol"]),
])
def test_wrong_hello_refused(provider: Path, frame_bytes: bytes, code: str,
                             words: list[str]) -> None:
    with connect(provider) as sock:
        sock.sendall(frame_bytes)
        answer = read_frame(sock)
        assert answer is not None and answer[0] == ERROR
        call_id, name, message = error_of(answer[1])
        assert (call_id, name) == (0, code)
        for word in words:
            assert word in message
        assert read_frame(sock) is None


def test_malformed_requests_answered_connection_kept(provider: Path) -> None:
    good = echo_payload(7, 1, b"hello")
    bad = {
        "truncated": good[:-1],
        "trailing byte": good + b"\x00",
        "count beyond the data": struct.pack("<IIII", 7, 1, 0, 1_000_000_000) + b"abc",
        "no fixed fields": b"\x01",
    }
    with greeted(provider) as sock:
        for call_id, payload in enumerate(bad.values(), start=10):
            sock.sendall(request(call_id, payload))
            answer = read_frame(sock)
            assert answer is not None and answer[0] == ERROR
            got_id, name, message = error_of(answer[1])
            assert (got_id, name) == (call_id, "EPROTOCOL")
            assert "malformed request" in message
        # Same connection, now a good request.
        sock.sendall(request(99, good))
        assert read_frame(sock) == (RESPONSE, struct.pack("<III", 99, 7, 1)
                                    + struct.pack("<I", 5) + b"hello")


def test_oversized_request_refused_before_reading_it(setup: Setup, provider: Path) -> None:
    with greeted(provider) as sock:
        # Only the header of a 10 MiB frame: the provider answers without waiting for it.
        sock.sendall(struct.pack("<IH", 10 << 20, REQUEST))
        answer = read_frame(sock)
        assert answer is not None and answer[0] == ERROR
        _, name, message = error_of(answer[1])
        assert name == "ETOOBIG"
        assert "exceeds the provider's maximum of 1024" in message
        assert read_frame(sock) is None
    # A C caller with a too big request gets the same error as its call's result.
    result = setup.call("arm.echo", "1", "1", str(LIMIT), "2000")
    assert result["ok"] == 0 and result["failed"] == 1
    assert "exceeds the provider's maximum" in result["first_error"]


def test_connections_dropped_mid_frame(setup: Setup, provider: Path) -> None:
    for cut in (1, 5, 6, 9, 20):
        with greeted(provider) as sock:
            sock.sendall(request(1, echo_payload(1, 1, b"partial"))[:cut])
    for cut in (3, 12):
        with connect(provider) as sock:
            sock.sendall(hello()[:cut])
    still_serves(setup)
