"""Service calls between C callers and C providers under load and failure: concurrent callers
against a thread pool, error responses, timeouts, a provider killed in the middle of a call
and restarted, and the provider's sockets disappearing with it."""

from __future__ import annotations

import json
import subprocess
import sys
import time

import pytest

from .conftest import LIMIT, Setup, stop


def test_concurrent_callers_against_thread_pool(setup: Setup) -> None:
    prov = setup.provider("arm.echo", "pool", "4")
    result = setup.call("arm.echo", "8", "10000", str(LIMIT), "48")
    assert result == {"ok": 80000, "mismatch": 0, "failed": 0, "first_error": ""}
    assert stop(prov) == 0


def test_callers_against_single_thread_loop(setup: Setup) -> None:
    prov = setup.provider("arm.echo", "loop")
    result = setup.call("arm.echo", "3", "1000", str(LIMIT), "300")
    assert result == {"ok": 3000, "mismatch": 0, "failed": 0, "first_error": ""}
    assert stop(prov) == 0


def once(setup: Setup, name: str, text: str, delay_us: int = 0,
         timeout: float = LIMIT) -> dict[str, str]:
    proc = setup.run("once", name, text, str(delay_us), str(timeout))
    out, err = proc.communicate(timeout=LIMIT * 2)
    assert proc.returncode == 0, err
    return json.loads(out)


def test_error_responses_carry_the_providers_text(setup: Setup) -> None:
    prov = setup.provider("arm.echo", "loop")
    failed = once(setup, "arm.echo", "fail")
    assert failed["rc"] == "ESERVICE"
    assert 'echo refuses "fail"' in failed["error"] and "arm.echo" in failed["error"]
    silent = once(setup, "arm.echo", "silent")
    assert silent["rc"] == "ESERVICE"
    assert "returned without responding" in silent["error"]
    # The provider goes on serving.
    assert once(setup, "arm.echo", "still here") == {"rc": "OK", "error": "",
                                                     "text": "still here"}
    assert stop(prov) == 0


def test_nobody_provides(setup: Setup) -> None:
    result = once(setup, "arm.nothing", "x")
    assert result["rc"] == "ENOTFOUND"
    assert "arm.nothing" in result["error"]


def test_timeout_then_next_call_succeeds(setup: Setup) -> None:
    prov = setup.provider("arm.echo", "pool", "2")
    caller = setup.run("once", "arm.echo", "slow", "500000", "0.05", "2",
                       stdin=subprocess.PIPE)
    assert caller.stdout is not None and caller.stdin is not None
    first = json.loads(caller.stdout.readline())
    assert first["rc"] == "ETIMEOUT"
    assert "no response" in first["error"]
    # Same handle, another text: the late answer to the first call ("slow") must never be
    # taken for the second one's.
    caller.stdin.write("quick 0\n")
    caller.stdin.flush()
    second = json.loads(caller.stdout.readline())
    assert second == {"rc": "OK", "error": "", "text": "quick"}
    caller.stdin.close()
    assert caller.wait(timeout=LIMIT) == 0
    assert once(setup, "arm.echo", "quick")["rc"] == "OK"
    assert stop(prov) == 0


def test_provider_killed_mid_call_then_restarted(setup: Setup) -> None:
    prov = setup.provider("arm.echo", "loop")
    assert len(setup.sockets()) == 1
    caller = setup.run("once", "arm.echo", "slow", "30000000", str(LIMIT), "2",
                       stdin=subprocess.PIPE)
    assert prov.stdout is not None and caller.stdout is not None and caller.stdin is not None
    assert prov.stdout.readline().strip() == "busy"  # the handler has the request
    prov.kill()
    prov.wait()
    first = json.loads(caller.stdout.readline())
    # ECONNECTION, not ETIMEOUT: the error came as soon as the provider died.
    assert first["rc"] == "ECONNECTION", first
    assert "closed the connection" in first["error"]

    again = setup.provider("arm.echo", "loop")
    caller.stdin.write("again 0\n")
    caller.stdin.flush()
    # The same handle finds the new provider by itself.
    second = json.loads(caller.stdout.readline())
    assert second == {"rc": "OK", "error": "", "text": "again"}
    caller.stdin.close()
    assert caller.wait(timeout=LIMIT) == 0
    assert stop(again) == 0


def test_socket_removed_when_provider_exits(setup: Setup) -> None:
    prov = setup.provider("arm.echo", "loop")
    sockets = setup.sockets()
    assert len(sockets) == 1
    assert stop(prov) == 0
    assert setup.sockets() == []


def listed(setup: Setup) -> list[dict[str, object]]:
    out = subprocess.run([sys.executable, "-m", "links_and_nodes.manager.frontends.listing", "--json"],
                         capture_output=True, text=True, env=setup.manager.env,
                         timeout=LIMIT, check=True)
    return json.loads(out.stdout)


@pytest.mark.parametrize("mode", [("loop",), ("pool", "2")])
def test_manager_lists_call_counts(setup: Setup, mode: tuple[str, ...]) -> None:
    prov = setup.provider("arm.echo", *mode)
    assert setup.call("arm.echo", "2", "300", str(LIMIT))["ok"] == 600
    for text in ("fail", "silent"):
        assert once(setup, "arm.echo", text)["rc"] == "ESERVICE"
    # Providers report while busy at most once a second and the rest when idle: the final
    # counts arrive without further calls.
    deadline = time.monotonic() + LIMIT
    while True:
        (entry,) = listed(setup)
        if entry["calls"] == 602 or time.monotonic() > deadline:
            break
        time.sleep(0.1)
    assert (entry["calls"], entry["errors"]) == (602, 2)
    assert entry["name"] == "arm.echo" and entry["md_name"] == "lntest/echo"
    assert entry["provider"] == "service_stress"
    assert entry["group"] == "echo"
    stop(prov)
    assert listed(setup) == []


# A caller with another host id than the provider's must use TCP.
ELSEWHERE = {"LN_HOST_ID": "another-host"}


@pytest.mark.parametrize("env", [{}, ELSEWHERE], ids=["unix", "tcp"])
def test_provider_restarted_between_calls(setup: Setup, env: dict[str, str]) -> None:
    prov = setup.provider("arm.echo", "loop")
    caller = setup.run("once", "arm.echo", "first", "0", str(LIMIT), "2",
                       stdin=subprocess.PIPE, env=env)
    assert caller.stdout is not None and caller.stdin is not None
    assert json.loads(caller.stdout.readline()) == {"rc": "OK", "error": "", "text": "first"}
    assert stop(prov) == 0
    again = setup.provider("arm.echo", "loop")
    # The idle connection points at the old provider; the call must notice before sending and
    # go to the new one.
    caller.stdin.write("second 0\n")
    caller.stdin.flush()
    assert json.loads(caller.stdout.readline()) == {"rc": "OK", "error": "", "text": "second"}
    caller.stdin.close()
    assert caller.wait(timeout=LIMIT) == 0
    assert stop(again) == 0


def test_tcp_callers_against_thread_pool(setup: Setup) -> None:
    prov = setup.provider("arm.echo", "pool", "3")
    proc = setup.run("call", "arm.echo", "4", "2000", str(LIMIT), "100", env=ELSEWHERE)
    out, err = proc.communicate(timeout=LIMIT * 3)
    assert json.loads(out) == {"ok": 8000, "mismatch": 0, "failed": 0, "first_error": ""}, err
    # And over TCP an error names the TCP address it used.
    proc = setup.run("once", "arm.echo", "fail", "0", str(LIMIT), env=ELSEWHERE)
    failed = json.loads(proc.communicate(timeout=LIMIT)[0])
    assert failed["rc"] == "ESERVICE"
    assert stop(prov) == 0


def test_tcp_provider_killed_mid_call(setup: Setup) -> None:
    prov = setup.provider("arm.echo", "loop")
    caller = setup.run("once", "arm.echo", "slow", "30000000", str(LIMIT), env=ELSEWHERE)
    assert prov.stdout is not None and caller.stdout is not None
    assert prov.stdout.readline().strip() == "busy"
    prov.kill()
    prov.wait()
    result = json.loads(caller.stdout.readline())
    assert result["rc"] == "ECONNECTION", result
    assert "tcp:" in result["error"]
