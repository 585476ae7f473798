"""The subprotocol front (foxglove_bridge/front.py): its handshake rewriting, relaying and
Origin check, in front of a stand-in server; ln_foxglove's rules and its command line's
refusals; all without a manager."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from links_and_nodes.foxglove_bridge.config import FoxgloveConfig
from links_and_nodes.foxglove_bridge.front import (
    LEGACY,
    SDK,
    Front,
    offered,
    origin_allowed,
    rewrite_request,
    rewrite_response,
)

from .conftest import LIMIT, require_tools


def request(*protocol_lines: str) -> bytes:
    lines = ["GET / HTTP/1.1", "Host: localhost:8765", "Upgrade: websocket",
             "Connection: Upgrade", "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==",
             "Sec-WebSocket-Version: 13", *protocol_lines]
    return ("\r\n".join(lines) + "\r\n\r\n").encode()


def test_old_name_only_is_asked_for_as_the_new_one() -> None:
    head, legacy = rewrite_request(request(f"Sec-WebSocket-Protocol: {LEGACY}"))
    assert legacy and offered(head) == [SDK]
    assert head.endswith(b"\r\n\r\n") and head.count(b"\r\n\r\n") == 1
    assert b"Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n" in head  # the rest untouched
    answer = (b"HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\n"
              b"Sec-WebSocket-Accept: s3pPLMBiTxaQ9kYGzzhZRbK+xOo=\r\n"
              b"Sec-WebSocket-Protocol: foxglove.sdk.v1\r\n\r\n")
    back = rewrite_response(answer)
    assert offered(back) == [LEGACY]
    assert back.startswith(b"HTTP/1.1 101 Switching Protocols\r\n")
    assert b"Sec-WebSocket-Accept: s3pPLMBiTxaQ9kYGzzhZRbK+xOo=\r\n" in back


def test_header_names_in_any_case_and_several_lines() -> None:
    head, legacy = rewrite_request(request("sec-websocket-protocol: x.v1",
                                           f"SEC-WEBSOCKET-PROTOCOL:{LEGACY} , y"))
    assert legacy and offered(head) == [SDK]


@pytest.mark.parametrize("lines", [
    (f"Sec-WebSocket-Protocol: {SDK}",),
    (f"Sec-WebSocket-Protocol: {LEGACY}, {SDK}",),  # the sdk picks its own
    ("Sec-WebSocket-Protocol: other.v1",),
    (),
])
def test_other_requests_pass_unchanged(lines: tuple[str, ...]) -> None:
    head = request(*lines)
    assert rewrite_request(head) == (head, False)


def test_an_answer_without_the_new_name_passes_unchanged() -> None:
    answer = b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n"
    assert rewrite_response(answer) == answer


def test_rules() -> None:
    config = FoxgloveConfig(exclude=["secret.*"])
    assert config.topic_rule("arm.state") is not None
    assert config.topic_rule("secret.key") is None
    assert config.service_rule("secret.door") is None
    config.add_topic_spec("arm.*,rate=50")
    config.add_topic_spec("cam.*,queued=8")
    config.add_service_spec("arm.*,timeout=2")
    config.check()
    arm = config.topic_rule("arm.state")
    assert arm is not None and (arm.rate, arm.queued, arm.depth) == (50.0, False, 1)
    cam = config.topic_rule("cam.image")
    assert cam is not None and (cam.queued, cam.depth) == (True, 8)
    assert config.topic_rule("other") is None  # rules given: only what they select
    service = config.service_rule("arm.set_gains")
    assert service is not None and service.timeout == 2.0
    assert config.service_rule("other") is None
    config.offer_services = False
    assert config.service_rule("arm.set_gains") is None


@pytest.mark.parametrize(("args", "text"), [
    (["--topic", "a,rate=0"], "rate must be a positive number"),
    (["--topic", "a,remote=x"], "remote= is an ln_zenoh option"),
    (["--topic", "a,queued=5000"], "queued=N needs N in 2..1024"),
    (["--topic", "a,bogus"], "unknown option 'bogus'"),
    (["--service", "a,timeout=-1"], "timeout must be positive"),
    (["--port", "70000"], "port must be 0..65535"),
    (["--direct", "--origin", "x"], "it does not go with --direct"),
])
def test_command_line_refusals(args: list[str], text: str) -> None:
    result = subprocess.run([sys.executable, "-m", "links_and_nodes.foxglove_bridge.cli",
                             "--manager", "127.0.0.1:1", *args], capture_output=True,
                            text=True, timeout=LIMIT)
    assert result.returncode == 2 and text in result.stderr, result.stderr


def test_unreachable_manager_is_an_error() -> None:
    require_tools()  # without foxglove-sdk: the same exit status for another reason
    result = subprocess.run([sys.executable, "-m", "links_and_nodes.foxglove_bridge.cli",
                             "--manager", "127.0.0.1:1", "--port", "0"], capture_output=True,
                            text=True, timeout=LIMIT)
    assert result.returncode == 1 and "cannot reach the manager" in result.stderr, \
        result.stderr


def test_without_the_sdk_one_error_line(tmp_path: Path) -> None:
    """As on a Debian system without pip's foxglove-sdk: a `foxglove` that fails to import."""
    (tmp_path / "foxglove").mkdir()
    (tmp_path / "foxglove" / "__init__.py").write_text('raise ImportError("not here")\n')
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(tmp_path), *filter(None, [os.environ.get("PYTHONPATH")])])}
    result = subprocess.run([sys.executable, "-m", "links_and_nodes.foxglove_bridge.cli",
                             "--manager", "127.0.0.1:1"], capture_output=True, text=True,
                            env=env, timeout=LIMIT)
    assert result.returncode == 1, result.stderr
    assert result.stderr.splitlines() == [
        "ln_foxglove: error: the Python package foxglove-sdk is not installed: pip install "
        "foxglove-sdk  (or: pip install 'links_and_nodes[foxglove]')"]


class FakeSdk:
    """A stand-in for the sdk's server behind the front: answers each handshake with 101 and
    the subprotocol it was asked for, then echoes bytes; records the request heads."""

    def __init__(self) -> None:
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]
        self.heads: list[bytes] = []
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self) -> None:
        while True:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            threading.Thread(target=self._one, args=(conn,), daemon=True).start()

    def _one(self, conn: socket.socket) -> None:
        with conn:
            data = b""
            while b"\r\n\r\n" not in data:
                data += conn.recv(4096)
            head, rest = data.split(b"\r\n\r\n", 1)
            self.heads.append(head + b"\r\n\r\n")
            names = offered(head + b"\r\n\r\n")
            conn.sendall(b"HTTP/1.1 101 Switching Protocols\r\n" + b"".join(
                b"Sec-WebSocket-Protocol: " + n.encode() + b"\r\n" for n in names[:1])
                + b"\r\n" + rest)
            while chunk := conn.recv(4096):
                conn.sendall(chunk)


def exchange(port: int, data: bytes) -> bytes:
    """Send `data`, close the sending side, return everything answered."""
    with socket.create_connection(("127.0.0.1", port), timeout=LIMIT) as s:
        s.sendall(data)
        s.shutdown(socket.SHUT_WR)
        answer = b""
        while chunk := s.recv(65536):
            answer += chunk
        return answer


def test_front_relays_and_checks_origins() -> None:
    sdk = FakeSdk()
    front = Front("127.0.0.1", 0, sdk.port, print, origins=["https://app.foxglove.dev"])
    try:
        body = b"frames" * 20000  # more than one read, sent with the head
        answer = exchange(front.port, request(f"Sec-WebSocket-Protocol: {LEGACY}") + body)
        head, _, echoed = answer.partition(b"\r\n\r\n")
        assert offered(head + b"\r\n\r\n") == [LEGACY] and echoed == body
        assert offered(sdk.heads[-1]) == [SDK]
        answer = exchange(front.port, request(f"Sec-WebSocket-Protocol: {SDK}",
                                              "Origin: https://app.foxglove.dev") + b"x")
        assert answer.endswith(b"\r\n\r\nx") and offered(answer) == [SDK]
        seen = len(sdk.heads)
        answer = exchange(front.port, request(f"Sec-WebSocket-Protocol: {SDK}",
                                              "Origin: http://evil.example"))
        assert answer.startswith(b"HTTP/1.1 403 ") and len(sdk.heads) == seen
        assert (front.connections, front.legacy_connections, front.refused) == (2, 1, 1)
    finally:
        front.close()
        sdk.sock.close()


def test_front_without_its_server_answers_503() -> None:
    gone = socket.create_server(("127.0.0.1", 0))
    port = gone.getsockname()[1]
    gone.close()
    front = Front("127.0.0.1", 0, port, lambda text: None)
    try:
        assert exchange(front.port, request()).startswith(b"HTTP/1.1 503 ")
    finally:
        front.close()


def test_origin_check() -> None:
    patterns = ["https://app.foxglove.dev", "http://localhost:*"]
    assert origin_allowed(request(), patterns)  # no Origin: not a browser
    assert origin_allowed(request("origin: http://localhost:8080"), patterns)
    assert not origin_allowed(request("Origin: https://app.foxglove.dev.evil.example"),
                              patterns)
    assert origin_allowed(request("Origin: http://evil.example"), [])  # no patterns: no check
