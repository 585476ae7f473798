"""Recording service calls through ServiceCallTap (docs/services.md, "Recording calls"): Python
and C providers, error answers, services that do not match, providers that come later, a
recorder killed with SIGKILL and one too slow to keep up."""

from __future__ import annotations

import os
import signal
import sys
import time
from typing import Any

import pytest
from polling import wait_for

import links_and_nodes as ln
from links_and_nodes.record.service_calls import (
    STATUS_ERROR,
    STATUS_OK,
    ServiceCall,
    ServiceCallTap,
    decode_call,
    encode_call,
)

from .conftest import Lab
from .service_lab import (
    LIMIT,
    echo_handler,
    echo_request,
    echo_response,
    plan_request,
    plan_response,
    serving,
    start_c_provider,
)

GOAL = [0.1 * j - 0.3 for j in range(7)]


def take(tap: ServiceCallTap, n: int) -> list[ServiceCall]:
    calls: list[ServiceCall] = []
    deadline = time.monotonic() + LIMIT
    while len(calls) < n and time.monotonic() < deadline:
        call = tap.get(0.1)
        if call is not None:
            calls.append(call)
    assert len(calls) == n, f"{len(calls)} of {n} calls recorded"
    return calls


def tapped(tap: ServiceCallTap, service: str) -> None:
    wait_for(lambda: service in tap.tapped, f"the tap on {service}")


def echo_call(svc: Any, seq: int, text: str) -> Any:
    svc.req.caller, svc.req.seq, svc.req.delay_us, svc.req.text = 7, seq, 0, text
    return svc.call(timeout=LIMIT)


def test_python_provider_calls_and_errors_recorded(lab: Lab) -> None:
    prov = lab.client("echo_provider")
    prov.get_service_provider("rec.echo", "lntest/echo", echo_handler)
    prov.get_service_provider("other.echo", "lntest/echo", echo_handler)
    caller = lab.client("echo_caller")
    with serving(prov), ServiceCallTap(lab.address, [r"rec\..*"], poll=0.05) as tap:
        tapped(tap, "rec.echo")
        assert "other.echo" not in tap.tapped
        svc = caller.get_service("rec.echo", "lntest/echo")
        other = caller.get_service("other.echo", "lntest/echo")
        before = time.time_ns()
        echo_call(svc, 1, "hello")
        echo_call(other, 2, "not recorded")
        with pytest.raises(ln.LnServiceError):
            echo_call(svc, 3, "fail")
        after = time.time_ns()
        ok, err = take(tap, 2)
        assert tap.get(0.3) is None  # other.echo's call is not there
    assert (ok.service, ok.md_name, ok.caller, ok.provider) == (
        "rec.echo", "lntest/echo", caller.name, prov.name)
    assert ok.layout_hash == ln.message_class("lntest/echo").LAYOUT_HASH
    assert ok.status == STATUS_OK and ok.code == 0 and ok.error == ""
    assert ok.request == echo_request(7, 1, b"hello")
    assert ok.response == echo_response(7, 1, b"hello")
    assert before <= ok.request_time_ns <= err.request_time_ns <= after
    assert 0 <= ok.duration_ns <= after - before
    assert err.status == STATUS_ERROR and err.error == "refused call 3"
    assert err.code == ln.LnServiceError.code and err.response == b""
    assert err.request == echo_request(7, 3, b"fail")
    # the MCAP message form round-trips
    for call in (ok, err):
        back = decode_call(encode_call(call), call.service, call.md_name, call.layout_hash)
        assert back == ServiceCall(**{**call.__dict__, "signature": ""})


def test_c_provider_recorded(lab: Lab) -> None:
    proc = start_c_provider(lab.env(), "rec.plan")
    lab.procs.append(proc)  # type: ignore[arg-type]
    caller = lab.client("plan_caller")
    with ServiceCallTap(lab.address, ["rec.plan"], poll=0.05) as tap:
        tapped(tap, "rec.plan")
        svc = caller.get_service("rec.plan", "robot/plan_path")
        svc.req.goal = GOAL
        svc.req.max_velocity = 0.5
        svc.req.constraints = [{"data": "joint_limits"}, {"data": "collision"}]
        svc.call(timeout=LIMIT)
        svc.req.constraints = [{"data": "fail"}]
        with pytest.raises(ln.LnServiceError):
            svc.call(timeout=LIMIT)
        ok, err = take(tap, 2)
    names = [b"joint_limits", b"collision"]
    assert (ok.caller, ok.provider, ok.md_name) == (caller.name, "service_tool",
                                                    "robot/plan_path")
    assert ok.request == plan_request(GOAL, 0.5, names)
    assert ok.response == plan_response(GOAL, 0.5, names)
    assert err.request == plan_request(GOAL, 0.5, [b"fail"])
    assert err.error == "constraint 0 is 'fail'"


def test_provider_registered_after_the_tap_is_recorded(lab: Lab) -> None:
    with ServiceCallTap(lab.address, [r"late\.echo"], poll=0.05) as tap:
        time.sleep(0.2)  # the tap has looked at the list without it
        assert tap.tapped == {}
        prov = lab.client("late_provider")
        prov.get_service_provider("late.echo", "lntest/echo", echo_handler)
        caller = lab.client("late_caller")
        with serving(prov):
            tapped(tap, "late.echo")
            echo_call(caller.get_service("late.echo", "lntest/echo"), 5, "late")
            (call,) = take(tap, 1)
    assert call.request == echo_request(7, 5, b"late")
    assert call.provider == prov.name


TAP_SCRIPT = """
import sys, time
from links_and_nodes.record.service_calls import ServiceCallTap
tap = ServiceCallTap(sys.argv[1], ["kill.echo"], poll=0.05)
while "kill.echo" not in tap.tapped:
    time.sleep(0.01)
print("tapped", flush=True)
time.sleep(600)
"""


def test_recorder_killed_leaves_the_provider_serving(lab: Lab) -> None:
    import subprocess

    prov = lab.client("kill_provider")
    prov.get_service_provider("kill.echo", "lntest/echo", echo_handler)
    caller = lab.client("kill_caller")
    with serving(prov):
        rec = subprocess.Popen([sys.executable, "-c", TAP_SCRIPT, lab.address],
                               stdout=subprocess.PIPE, text=True, env=lab.env())
        lab.procs.append(rec)  # type: ignore[arg-type]
        assert rec.stdout is not None and rec.stdout.readline().strip() == "tapped"
        svc = caller.get_service("kill.echo", "lntest/echo")
        for seq in range(20):
            assert echo_call(svc, seq, "before").seq == seq
        os.kill(rec.pid, signal.SIGKILL)
        rec.wait()
        for seq in range(200):  # a hang here would hit the call timeout, never pass
            svc.req.text = "x" * 4096
            svc.req.seq = seq
            assert svc.call(timeout=5.0).seq == seq
        # and a new recorder taps it again
        with ServiceCallTap(lab.address, ["kill.echo"], poll=0.05) as tap:
            tapped(tap, "kill.echo")
            echo_call(svc, 999, "after")
            (call,) = take(tap, 1)
    assert call.request == echo_request(7, 999, b"after")


def test_slow_recorder_counts_drops_instead_of_blocking(lab: Lab) -> None:
    prov = lab.client("slow_provider")
    prov.get_service_provider("slow.echo", "lntest/echo", echo_handler)
    caller = lab.client("slow_caller")
    text = "y" * (64 << 10)
    total = 300  # 300 x 64 KiB: more than the provider's tap queue and the socket hold
    with serving(prov), ServiceCallTap(lab.address, ["slow.echo"], poll=0.05,
                                       queue_size=1) as tap:
        tapped(tap, "slow.echo")
        svc = caller.get_service("slow.echo", "lntest/echo")
        for seq in range(total - 1):  # nobody takes calls out of the tap meanwhile
            assert echo_call(svc, seq, text).seq == seq
        received = []
        while (call := tap.get(1.0)) is not None:
            received.append(call)
        echo_call(svc, total - 1, "last")
        while not received or received[-1].request != echo_request(7, total - 1, b"last"):
            call = tap.get(LIMIT)
            assert call is not None, "the last call never came"
            received.append(call)
        drops = tap.drops
    assert drops > 0
    assert len(received) + drops == total
    seqs = [int.from_bytes(c.request[4:8], "little") for c in received]
    assert seqs == sorted(seqs)
