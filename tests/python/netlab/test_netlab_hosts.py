"""The lab's hosts are separate machines as far as links_and_nodes can tell: they reach each
other only over the lab's bridge, and each has its own /dev/shm, /tmp/ln-<uid>, hostname and
LN_HOST_ID, also against the hosts of another lab running at the same time."""

from __future__ import annotations

import os
import socket
import uuid
from pathlib import Path

from netlab import NetLab
from polling import wait_for


def test_hosts_ping_each_other_over_the_bridge(netlab: NetLab) -> None:
    a, b = netlab["a"], netlab["b"]
    assert (a.address, b.address) == ("10.77.0.1", "10.77.0.2")
    assert a.ping(b.address) and b.ping(a.address)
    mgr = netlab.add_host("mgr")
    assert mgr.address == "10.77.0.3"
    assert mgr.ping(a.address) and a.ping(mgr.address)
    # Names resolve as on a LAN: the short name and the host id (also the hostname).
    got = mgr.run(["getent", "hosts", "a", a.host_id], check=True).stdout.split()
    assert got == [a.address, a.host_id, "a", a.address, a.host_id, "a"]


def test_a_disconnected_host_is_unreachable_until_reconnected(netlab: NetLab) -> None:
    a, b = netlab["a"], netlab["b"]
    assert b.ping(a.address)
    a.disconnect()
    assert not b.ping(a.address, timeout=0.5)
    assert not a.ping(b.address, timeout=0.5)
    a.reconnect()
    wait_for(lambda: b.ping(a.address), "a to answer again after reconnect()")


def test_each_host_has_its_own_dev_shm_and_runtime_dir(netlab: NetLab) -> None:
    a, b = netlab["a"], netlab["b"]
    marker = f"netlab-marker-{uuid.uuid4().hex}"
    runtime = f"/tmp/ln-{os.getuid()}"
    a.run(["sh", "-c", f"echo a > /dev/shm/{marker} && echo a > {runtime}/{marker}"],
          check=True)
    assert a.run(["cat", f"/dev/shm/{marker}", f"{runtime}/{marker}"]).stdout == "a\na\n"
    for path in (f"/dev/shm/{marker}", f"{runtime}/{marker}"):
        assert b.run(["test", "-e", path]).returncode == 1, f"{path} is visible on b"
        assert not Path(path).exists(), f"{path} is visible outside the lab"
        assert a.path(path).read_text() == "a\n" and not b.path(path).exists()
    assert a.run(["stat", "-c", "%a", "/dev/shm"]).stdout.strip() == "1777"


def test_host_ids_and_hostnames_differ_between_hosts_and_labs(netlab: NetLab,
                                                                tmp_path: Path) -> None:
    show = ["sh", "-c", 'echo "$LN_HOST_ID $(hostname)"']
    with NetLab(tmp_path / "second", hosts=["a"]) as other:
        seen = [h.run(show, check=True).stdout.split()
                for h in (netlab["a"], netlab["b"], other["a"])]
    for host_id, hostname in seen:
        assert host_id == hostname  # libln's fallback (hostname/boot_id) differs as well
    ids = [s[0] for s in seen]
    assert len(set(ids)) == 3 and socket.gethostname() not in ids
    assert ids[0] == netlab["a"].host_id


def test_caller_environment_that_points_outside_the_host_is_dropped(netlab: NetLab,
                                                                     monkeypatch) -> None:
    monkeypatch.setenv("LN_RUNTIME_DIR", "/tmp/shared-runtime")
    monkeypatch.setenv("LN_MANAGER", "127.0.0.1:1")
    monkeypatch.setenv("NETLAB_KEPT", "yes")
    env = netlab["a"].env()
    assert "LN_RUNTIME_DIR" not in env and "LN_MANAGER" not in env
    assert env["NETLAB_KEPT"] == "yes" and env["LN_HOST_ID"] == netlab["a"].host_id


def test_popen_runs_in_the_host_and_logs_to_the_lab_directory(netlab: NetLab) -> None:
    a = netlab["a"]
    proc = a.popen(["sh", "-c", "hostname; echo oops >&2; exec sleep 1000"])
    wait_for(lambda: proc.log_path and proc.log_path.read_text() == f"{a.host_id}\noops\n",
             "the process's output in its log")
    assert proc.log_path.parent == netlab.directory
    assert proc.pid in a.pids() and proc.pid not in netlab["b"].pids()
