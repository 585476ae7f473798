"""Service calls between hosts under each `security` level (docs/security.md, "Remote service
calls"): C callers forced onto TCP reach a C provider with none, authenticate and encrypt; a
man in the middle that flips a byte, replays or truncates a frame makes that call fail with
LN_EPERM, the frame never reaches the handler and the provider keeps serving; with encrypt a
request's text does not cross the wire; callers that do not protect their connection (or ask
for another level) are refused."""

from __future__ import annotations

import json
import socket
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from .conftest import LIMIT, REPO, Setup, private_manager, stop
from .test_service_wire import MAGIC, error_of, frame, hello, read_exact, read_frame, text

ELSEWHERE = {"LN_HOST_ID": "another-host"}  # another host id than the provider's: TCP
# The provider listens on 127.0.0.1 only and advertises 127.0.0.2, where the relay sits.
RELAYED = {"LN_SERVICE_HOST": "127.0.0.2", "LN_SERVICE_BIND": "127.0.0.1"}
SECURE, SECURED, SEALED = 9, 10, 11
LEVELS = {"none": 0, "authenticate": 1, "encrypt": 2}
# tamper(direction "up" (caller -> provider) or "down", frames of that direction so far, frame)
Tamper = Callable[[str, list[bytes], bytes], bytes]


@pytest.fixture
def secured(tmp_path: Path, request: pytest.FixtureRequest) -> Iterator[Setup]:
    """A private manager with --service-security given by the test's parameter."""
    yield from private_manager(tmp_path, "--service-security", request.param)


class Relay:
    """A man in the middle at 127.0.0.2:PORT in front of a provider at 127.0.0.1:PORT: passes
    whole frames both ways, keeps every byte it saw, and lets `tamper` change a frame."""

    def __init__(self, port: int, tamper: Tamper | None = None) -> None:
        self.port = port
        self.tamper = tamper
        self.seen = bytearray()
        self._lock = threading.Lock()
        self._server = socket.create_server(("127.0.0.2", port))
        self._server.settimeout(0.2)
        self._stop = threading.Event()
        self._threads = [threading.Thread(target=self._accept, daemon=True)]
        self._threads[0].start()

    def _accept(self) -> None:
        while not self._stop.is_set():
            try:
                caller, _ = self._server.accept()
            except TimeoutError:
                continue
            provider = socket.create_connection(("127.0.0.1", self.port), timeout=LIMIT)
            for src, dst, direction in ((caller, provider, "up"), (provider, caller, "down")):
                t = threading.Thread(target=self._pipe, args=(src, dst, direction), daemon=True)
                t.start()
                self._threads.append(t)

    def _pipe(self, src: socket.socket, dst: socket.socket, direction: str) -> None:
        frames: list[bytes] = []
        try:
            while True:
                header = read_exact(src, 6)
                body = read_exact(src, struct.unpack("<I", header[:4])[0] - 2) if header else None
                if header is None or body is None:
                    break
                whole = header + body
                with self._lock:
                    self.seen += whole
                out = self.tamper(direction, frames, whole) if self.tamper else whole
                frames.append(whole)
                dst.sendall(out)
        except OSError:
            pass
        finally:
            for sock in (src, dst):
                try:
                    sock.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass

    def close(self) -> None:
        self._stop.set()
        self._threads[0].join(timeout=LIMIT)  # it polls the flag 5 times a second
        self._server.close()


def relayed_provider(setup: Setup, *mode: str) -> subprocess.Popen[str]:
    """An echo provider that advertises the relay's address; returns once ready."""
    proc = setup.run("provide", "arm.echo", *mode, stdin=subprocess.PIPE, env=RELAYED)
    assert proc.stdout is not None
    line = proc.stdout.readline()
    assert line.strip() == "ready", f"provider did not start: {line!r}"
    return proc


def provider_entry(setup: Setup) -> dict[str, object]:
    out = subprocess.run([sys.executable, "-m", "links_and_nodes.manager.frontends.listing",
                          "--json"], capture_output=True, text=True, env=setup.manager.env,
                         timeout=LIMIT, check=True)
    (entry,) = json.loads(out.stdout)
    return entry


def counts_become(setup: Setup, calls: int, errors: int) -> tuple[int, int]:
    """The provider's (calls, errors) as the manager lists them, once they are `calls` (the
    provider reports when idle) or the limit passed."""
    deadline = time.monotonic() + LIMIT
    while True:
        entry = provider_entry(setup)
        got = (int(entry["calls"]), int(entry["errors"]))  # type: ignore[call-overload]
        if got == (calls, errors) or time.monotonic() > deadline:
            return got
        time.sleep(0.1)


def two_calls(setup: Setup, first: str, second: str) -> list[dict[str, str]]:
    """Two calls on one TCP connection; their JSON results."""
    caller = setup.run("once", "arm.echo", first, "0", str(LIMIT), "2", stdin=subprocess.PIPE,
                       env=ELSEWHERE)
    assert caller.stdout is not None and caller.stdin is not None
    results = [json.loads(caller.stdout.readline())]
    caller.stdin.write(f"{second} 0\n")
    caller.stdin.flush()
    results.append(json.loads(caller.stdout.readline()))
    caller.stdin.close()
    caller.wait(timeout=LIMIT)
    return results


def one_call(setup: Setup, text_: str) -> dict[str, str]:
    proc = setup.run("once", "arm.echo", text_, "0", str(LIMIT), env=ELSEWHERE)
    out, err = proc.communicate(timeout=LIMIT)
    assert out.strip(), err
    return json.loads(out)


@pytest.mark.parametrize("secured", list(LEVELS), indirect=True)
def test_calls_between_hosts_at_each_level(secured: Setup) -> None:
    prov = secured.provider("arm.echo", "pool", "2")
    result = secured.call("arm.echo", "3", "300", str(LIMIT), "200")
    assert result == {"ok": 900, "mismatch": 0, "failed": 0, "first_error": ""}  # Unix
    proc = secured.run("call", "arm.echo", "2", "500", str(LIMIT), "64", env=ELSEWHERE)
    out, err = proc.communicate(timeout=LIMIT * 3)
    assert json.loads(out) == {"ok": 1000, "mismatch": 0, "failed": 0, "first_error": ""}, err
    # An error response travels protected too.
    assert one_call(secured, "fail")["rc"] == "ESERVICE"
    assert stop(prov) == 0


@pytest.mark.parametrize("secured", list(LEVELS), indirect=True)
def test_request_text_on_the_wire(secured: Setup, request: pytest.FixtureRequest) -> None:
    prov = relayed_provider(secured, "loop")
    relay = Relay(int(provider_entry(secured)["tcp_port"]))  # type: ignore[call-overload]
    try:
        marker = "robot-arm-secret-4711"
        assert one_call(secured, marker) == {"rc": "OK", "error": "", "text": marker}
        on_wire = marker.encode() in relay.seen
        assert on_wire == (request.node.callspec.params["secured"] != "encrypt")
        if request.node.callspec.params["secured"] != "none":
            assert bytes([SEALED, 0]) in relay.seen  # the frames went sealed
    finally:
        relay.close()
    assert stop(prov) == 0


def flip(direction: str, index: int) -> Tamper:
    def tamper(d: str, before: list[bytes], whole: bytes) -> bytes:
        if d != direction or len(before) != index:
            return whole
        changed = bytearray(whole)
        changed[12] ^= 0x01  # inside the sealed frame, past its header
        return bytes(changed)
    return tamper


def replay(d: str, before: list[bytes], whole: bytes) -> bytes:
    """The second request replaced by the first (a recorded, valid frame)."""
    return before[2] if d == "up" and len(before) == 3 else whole


def truncate(d: str, before: list[bytes], whole: bytes) -> bytes:
    """The second request cut by 8 bytes, its length made to match."""
    if d != "up" or len(before) != 3:
        return whole
    body = whole[6:-8]
    return struct.pack("<I", len(body) + 2) + whole[4:6] + body


# Frames of one connection: up SECURE, HELLO, REQUEST, REQUEST; down SECURED, WELCOME,
# RESPONSE, RESPONSE.  Each attack hits the second call.
ATTACKS = {"flip-request": (flip("up", 3), True), "replay-request": (replay, True),
           "truncate-request": (truncate, True), "flip-response": (flip("down", 3), False)}


@pytest.mark.parametrize("secured", ["authenticate", "encrypt"], indirect=True)
@pytest.mark.parametrize("attack", list(ATTACKS))
def test_tampered_frame_fails_the_call(secured: Setup, attack: str) -> None:
    tamper, upstream = ATTACKS[attack]
    prov = relayed_provider(secured, "pool", "2")
    relay = Relay(int(provider_entry(secured)["tcp_port"]), tamper)  # type: ignore[call-overload]
    try:
        first, second = two_calls(secured, "before", "attacked")
        assert first == {"rc": "OK", "error": "", "text": "before"}
        assert second["rc"] == "EPERM", second
        assert "failed authentication" in second["error"], second
        assert "arm.echo" in second["error"]
        # The provider serves the next caller, and the altered request never reached the
        # handler (a request the provider took counts as a call).
        relay.tamper = None
        assert one_call(secured, "after") == {"rc": "OK", "error": "", "text": "after"}
        expected = (2, 1) if upstream else (3, 0)
        assert counts_become(secured, *expected) == expected
    finally:
        relay.close()
    assert stop(prov) == 0


# A Python caller (libln through ctypes) in its own process, so that its host id differs.
PY_CALLER = """
import sys
import links_and_nodes as ln
ln.add_message_definition_dir(sys.argv[1])
with ln.client("py_caller") as clnt:
    svc = clnt.get_service("arm.echo", "lntest/echo")
    for seq in range(50):
        svc.req.caller, svc.req.seq, svc.req.text = 7, seq, f"python {seq}"
        resp = svc.call(timeout=60.0)
        assert (resp.caller, resp.seq, resp.text) == (7, seq, f"python {seq}"), resp
    svc.req.text = "fail"
    try:
        svc.call(timeout=60.0)
    except ln.LnServiceError as exc:
        print("refused:", exc)
print("ok")
"""


@pytest.mark.parametrize("secured", ["encrypt"], indirect=True)
def test_python_caller_over_tcp(secured: Setup) -> None:
    prov = secured.provider("arm.echo", "pool", "2")
    proc = subprocess.run([sys.executable, "-c", PY_CALLER,
                           str(REPO / "tests" / "fixtures" / "md" / "services")],
                          env={**secured.manager.env, **ELSEWHERE}, capture_output=True,
                          text=True, timeout=LIMIT * 2)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[-1] == "ok" and 'echo refuses "fail"' in lines[0], proc.stdout
    assert stop(prov) == 0


def secure_frame(level: int, name: str = "arm.echo") -> bytes:
    return frame(SECURE, struct.pack("<IHHH", MAGIC, 1, level, 3) + text(name) + bytes(32))


def refusal(port: int, first: bytes) -> tuple[int, str, str]:
    """The provider's answer to `first` on a new TCP connection: an ERROR, then it closes."""
    with socket.create_connection(("127.0.0.1", port), timeout=LIMIT) as sock:
        sock.sendall(first)
        answer = read_frame(sock)
        assert answer is not None and answer[0] == 5, answer
        assert read_exact(sock, 1) is None  # closed
        return error_of(answer[1])


@pytest.mark.parametrize("secured", ["authenticate"], indirect=True)
def test_unprotected_or_other_level_callers_are_refused(secured: Setup) -> None:
    prov = secured.provider("arm.echo", "loop")
    port = int(provider_entry(secured)["tcp_port"])  # type: ignore[call-overload]
    _, code, why = refusal(port, hello())
    assert code == "EPERM" and "only protected (security authenticate)" in why, why
    _, code, why = refusal(port, secure_frame(LEVELS["encrypt"]))
    assert code == "EPERM" and "security authenticate, the caller asks for encrypt" in why, why
    _, code, why = refusal(port, secure_frame(LEVELS["authenticate"], "arm.other"))
    assert code == "ENOTFOUND", why
    assert one_call(secured, "still") == {"rc": "OK", "error": "", "text": "still"}
    assert stop(prov) == 0


@pytest.mark.parametrize("secured", ["none"], indirect=True)
def test_protected_caller_refused_by_a_provider_without_security(secured: Setup) -> None:
    prov = secured.provider("arm.echo", "loop")
    port = int(provider_entry(secured)["tcp_port"])  # type: ignore[call-overload]
    _, code, why = refusal(port, secure_frame(LEVELS["authenticate"]))
    assert code == "EPERM" and "has security none" in why, why
    assert stop(prov) == 0
