"""Leaving a lab removes everything it made, also when the test fails inside it; labs whose
creator died are swept by the next lab; where no lab can be made, tests skip saying why."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import netlab as netlab_module
import pytest
from netlab import NetLab, namespace_pids, namespaces, sweep_stale
from polling import wait_for


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state not in ("Z", "X")


def lab_namespaces(lab: NetLab) -> list[str]:
    return [n for n in namespaces() if n.startswith(f"{lab.name}-")]


def populate(lab: NetLab) -> list[int]:
    """Start something everywhere: a daemon, a plain process, one that left its session."""
    a, b = lab["a"], lab["b"]
    pids = [a.start_daemon().pid, b.popen(["sleep", "1000"]).pid]
    escape = b.popen(["setsid", "-f", "sleep", "1000"])
    assert escape.wait(netlab_module.WAIT) == 0  # it has forked the sleep, which lives on
    pids += b.pids() + a.pids()
    assert len(pids) == 2 + 3 + 2  # + b's anchor, sleep, escaped sleep; a's anchor, daemon
    assert sorted(lab_namespaces(lab)) == sorted([lab.switch, a.netns, b.netns])
    return pids


def test_leaving_the_lab_removes_namespaces_and_processes(tmp_path: Path) -> None:
    netlab_module.require_netlab()
    with NetLab(tmp_path) as lab:
        pids = populate(lab)
    assert lab_namespaces(lab) == []
    assert [pid for pid in pids if alive(pid)] == []


def test_a_failing_test_still_cleans_up(tmp_path: Path) -> None:
    netlab_module.require_netlab()
    with pytest.raises(RuntimeError, match="the test failed"), NetLab(tmp_path) as lab:
        pids = populate(lab)
        raise RuntimeError("the test failed")
    assert lab_namespaces(lab) == []
    assert [pid for pid in pids if alive(pid)] == []


def test_stale_labs_of_dead_creators_are_swept() -> None:
    netlab_module.require_netlab()
    # A prefix of this test only, so that concurrent labs do not sweep it first.
    prefix = f"lnlabsweep{os.getpid()}q"
    dead = subprocess.Popen(["true"])
    dead.wait()
    living = f"{prefix}{os.getpid()}x1-a"
    stale = f"{prefix}{dead.pid}x1-a"
    for name in (living, stale):
        subprocess.run(["ip", "netns", "add", name], check=True)
    orphan = subprocess.Popen(["ip", "netns", "exec", stale, "sleep", "1000"])
    try:
        # until `ip netns exec` has entered the namespace there is nothing there to kill
        wait_for(lambda: orphan.pid in namespace_pids(stale), "the orphan in its namespace")
        assert sweep_stale(prefix) == [stale]
        assert orphan.wait(timeout=netlab_module.WAIT) == -9
        assert stale not in namespaces() and living in namespaces()
    finally:
        orphan.kill()
        orphan.wait()
        for name in (living, stale):
            subprocess.run(["ip", "netns", "del", name], capture_output=True)


def test_unavailable_namespaces_skip_with_the_reason(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(netlab_module, "netlab_available", lambda: "no CAP_NET_ADMIN")
    monkeypatch.delenv("CI", raising=False)
    with pytest.raises(pytest.skip.Exception,
                       match="^network namespaces unavailable: no CAP_NET_ADMIN$"):
        netlab_module.require_netlab()
    monkeypatch.setenv("CI", "1")
    with pytest.raises(pytest.fail.Exception, match="no CAP_NET_ADMIN"):
        netlab_module.require_netlab()

