"""Helpers of the service-call recording tests: a Python provider of lntest/echo served in a
thread, the C service_tool as a provider of robot/plan_path, and the services' wire form
written out by hand (docs/message_definitions.md, "Serialized form") to compare recorded
bytes with."""

from __future__ import annotations

import contextlib
import struct
import subprocess
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest
from buildtree import build_dir

import links_and_nodes as ln

REPO = Path(__file__).resolve().parents[3]
ln.add_message_definition_dir(REPO / "tests" / "fixtures" / "md" / "services")
SERVICE_TOOL = build_dir() / "tests" / "c" / "tools" / "service_tool"
LIMIT = 60.0  # seconds: an upper bound against hangs, never a pass criterion


def echo_handler(request: ln.service_request) -> None:
    """lntest/echo: repeats caller, seq and text; text "fail" is answered with an error."""
    req = request.req
    if req.text == "fail":
        request.respond_error(f"refused call {req.seq}")
        return
    request.respond({"caller": req.caller, "seq": req.seq, "text": req.text})


def echo_request(caller: int, seq: int, text: bytes, delay_us: int = 0) -> bytes:
    return struct.pack("<IIII", caller, seq, delay_us, len(text)) + text


def echo_response(caller: int, seq: int, text: bytes) -> bytes:
    return struct.pack("<III", caller, seq, len(text)) + text


def plan_request(goal: list[float], max_velocity: float, constraints: list[bytes]) -> bytes:
    out = struct.pack("<8d", *goal, max_velocity) + struct.pack("<I", len(constraints))
    for c in constraints:
        out += struct.pack("<I", len(c)) + c
    return out


def plan_response(goal: list[float], max_velocity: float, constraints: list[bytes]) -> bytes:
    """What service_tool answers (tests/c/tools/service_tool.c)."""
    out = struct.pack("<I", len(constraints))
    for i, c in enumerate(constraints):
        out += struct.pack("<dI", i / 2, i) + struct.pack("<7d", *(g + i for g in goal))
        out += struct.pack("<7d", *[max_velocity] * 7)
        out += struct.pack("<7d", *(len(c) + j for j in range(7)))
    message = b",".join(constraints)
    return out + struct.pack("<iI", len(constraints), len(message)) + message


@contextlib.contextmanager
def serving(clnt: ln.client) -> Iterator[None]:
    """Handle `clnt`'s default group in a thread until the block ends."""
    stop = threading.Event()
    errors: list[BaseException] = []

    def run() -> None:
        try:
            while not stop.is_set():
                clnt.wait_and_handle_service_group_requests(None, timeout=0.05)
        except BaseException as exc:  # noqa: BLE001 - reported by the test
            errors.append(exc)

    thread = threading.Thread(target=run, name="serving")
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join(LIMIT)
    assert not thread.is_alive(), "the serving thread hangs"
    assert not errors, errors


def start_c_provider(env: dict[str, str], name: str) -> subprocess.Popen[str]:
    """`service_tool provide NAME` (robot/plan_path), once it said "ready"."""
    if not SERVICE_TOOL.exists():
        pytest.fail(f"{SERVICE_TOOL} is missing: run scons first")
    proc = subprocess.Popen([str(SERVICE_TOOL), "provide", name], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)
    assert proc.stdout is not None
    line = proc.stdout.readline()
    assert line.strip() == "ready", proc.stderr.read() if proc.stderr else line
    return proc
