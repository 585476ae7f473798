"""The C++ wrapper (ln.hpp) against the C API: a C++ provider answers C callers (explicit and
implicit responses, an exception as error text, thread-pool handling) and a C++ caller calls a
C provider."""

from __future__ import annotations

import json
import subprocess

import pytest

from .conftest import LIMIT, STRESS, Setup, stop

ECHO_CPP = STRESS.parent / "service_echo_cpp"


def cpp_provider(setup: Setup, name: str, *mode: str) -> subprocess.Popen[str]:
    proc = subprocess.Popen([str(ECHO_CPP), "provide", name, *mode], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=setup.manager.env)
    setup.tools.append(proc)
    assert proc.stdout is not None
    assert proc.stdout.readline().strip() == "ready", proc.stderr.read() if proc.stderr else ""
    return proc


def c_once(setup: Setup, name: str, text: str) -> dict[str, str]:
    proc = setup.run("once", name, text, "0", str(LIMIT))
    out, err = proc.communicate(timeout=LIMIT)
    assert proc.returncode == 0, err
    return json.loads(out)


@pytest.mark.parametrize("mode", [(), ("pool",)])
def test_cpp_provider_c_callers(setup: Setup, mode: tuple[str, ...]) -> None:
    prov = cpp_provider(setup, "cpp.echo", *mode)
    assert c_once(setup, "cpp.echo", "implicit") == {"rc": "OK", "error": "", "text": "implicit"}
    assert c_once(setup, "cpp.echo", "reply") == {"rc": "OK", "error": "", "text": "reply"}
    failed = c_once(setup, "cpp.echo", "fail")
    assert failed["rc"] == "ESERVICE"
    assert 'C++ echo refuses "fail"' in failed["error"]
    result = setup.call("cpp.echo", "4", "2000", str(LIMIT), "40")
    assert result == {"ok": 8000, "mismatch": 0, "failed": 0, "first_error": ""}
    assert stop(prov) == 0


def test_cpp_caller_c_provider(setup: Setup) -> None:
    prov = setup.provider("c.echo", "loop")
    for text, rc in (("from C++", "OK"), ("fail", "ESERVICE")):
        out = subprocess.run([str(ECHO_CPP), "once", "c.echo", text], capture_output=True,
                             text=True, env=setup.manager.env, timeout=LIMIT, check=True)
        assert json.loads(out.stdout) == {"rc": rc, "text": text if rc == "OK" else ""}
    assert stop(prov) == 0
