"""Lifetime of what the manager owns: ports die with their client's connection, segments
with their topic's last port, all of them with the manager (SIGTERM), and those of a killed
manager at the next start of its instance.  One manager per instance: the lock."""

from __future__ import annotations

import os
import signal
import stat
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import lnwire
import pytest
from mgrproc import WAIT, Manager, require_manager_library, segments, unique_instance, wait_for

require_manager_library()

import links_and_nodes as ln  # noqa: E402  (after the skip check)

Start = Callable[..., Manager]


def test_disconnect_releases_ports_and_segments(manager: Manager) -> None:
    inst = manager.instance
    observer = manager.client("observer")
    publisher = manager.client("publisher")
    subscriber = manager.client("subscriber")
    assert publisher.publish("state", "m/d", 1, 64).type == lnwire.PORT_OK
    assert subscriber.subscribe("state", "m/d", 1, 64, buffers=8).type == lnwire.PORT_OK
    assert subscriber.subscribe("private", "m/d", 1, 64).type == lnwire.PORT_OK
    assert segments(inst) == [f"ln.{inst}.1.1", f"ln.{inst}.1.2", f"ln.{inst}.2.1"]

    publisher.close()
    wait_for(lambda: observer.topic_info("state").publishers == 0, "the publisher's release")
    info = observer.topic_info("state")
    assert (info.type, info.subscribers) == (lnwire.TOPIC_INFO_OK, 1)
    assert len(segments(inst)) == 3  # the topic still has a port

    subscriber.close()
    manager.wait_log(r"client subscriber \(.*\): disconnected, released 2 ports")
    assert observer.topic_info("state").code == ln.LnNotfoundError.code
    assert observer.topic_info("private").code == ln.LnNotfoundError.code
    assert segments(inst) == []
    manager.wait_log(rf"topic 'state' has no ports left: removed /ln\.{inst}\.1\.1, "
                     rf"/ln\.{inst}\.1\.2")
    observer.close()


def test_a_killed_client_is_released(manager: Manager) -> None:
    """SIGKILL of a client process closes its socket like any exit."""
    script = ("import sys, lnwire; c = lnwire.WireClient(int(sys.argv[1])); c.hello('doomed');"
              "r = c.publish('t', 'm/d', 1, 8); print(r.segment, flush=True); sys.stdin.read()")
    child = subprocess.Popen([sys.executable, "-c", script, str(manager.port)],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                             cwd=Path(__file__).parent, env=dict(os.environ, PYTHONPATH=str(
                                 Path(__file__).parent)))
    assert child.stdout is not None
    segment = child.stdout.readline().decode().strip()
    assert segment == f"/ln.{manager.instance}.1.1"
    child.kill()
    child.wait(WAIT)
    child.stdout.close()
    assert child.stdin is not None
    child.stdin.close()
    manager.wait_log(r"client doomed \(.*\): disconnected, released 1 port$")
    assert segments(manager.instance) == []


def test_sigterm_closes_clients_and_unlinks_everything(manager: Manager) -> None:
    client = manager.client("ctl")
    client.publish("a", "m/d", 1, 8)
    client.subscribe("a", "m/d", 1, 8, buffers=3)
    client.subscribe("b", "m/d", 1, 8)
    assert len(segments(manager.instance)) == 3
    assert manager.stop(signal.SIGTERM) == 0
    assert client.closed_by_peer()
    assert segments(manager.instance) == []
    assert "shutting down: closing 1 client" in manager.log()


def test_sigint_is_a_clean_stop_too(manager: Manager) -> None:
    with manager.client("ctl") as client:
        client.publish("a", "m/d", 1, 8)
        assert manager.stop(signal.SIGINT) == 0
    assert segments(manager.instance) == []


@pytest.mark.parametrize("window", ["0", "0.5"])
def test_restart_after_sigkill_purges_only_its_instance(start_manager: Start, instance: str,
                                                        window: str) -> None:
    """Nobody comes back: with --adopt-window 0 the stale segments go before the ready line,
    with a window once it is over; other instances' segments stay either way."""
    first = start_manager(instance)
    # neighbours: another instance, and one whose name starts with ours
    others = [start_manager(unique_instance()), start_manager(f"{instance}_x")]
    kept = {}  # connected clients, one per manager
    for manager in [first, *others]:
        client = kept[manager.instance] = manager.client("ctl")
        client.publish("t1", "m/d", 1, 8)
        client.subscribe("t1", "m/d", 1, 8, buffers=4)
        client.publish("t2", "m/d", 1, 8)
    before = {m.instance: segments(m.instance) for m in others}
    assert len(segments(instance)) == 3

    first.kill()  # SIGKILL: no chance to clean up
    assert len(segments(instance)) == 3

    second = start_manager(instance, "--adopt-window", window, runtime=first.runtime)
    if window == "0":
        assert segments(instance) == []  # gone before the ready line
        second.wait_log(rf"removed 3 stale segments of instance '{instance}'")
    else:
        second.wait_log(r"adopted topic 't1': md 'm/d' \(hash 0x0000000000000001, 8 bytes\), "
                        r"5 slots, sample 0, 1 reader slot held")
        second.wait_log(r"adopted topic 't2' was not taken back: removed ")
        wait_for(lambda: segments(instance) == [], "the adopted segments removed")
    assert {m.instance: segments(m.instance) for m in others} == before
    for manager in others:
        info = kept[manager.instance].topic_info("t1")
        assert (info.publishers, info.subscribers) == (1, 1)
    with second.client("ctl") as client:  # and the new manager works
        # topic ids go on after the adopted ones
        topic_id = 1 if window == "0" else 3
        assert client.publish("t1", "m/d", 1, 8).segment == f"/ln.{instance}.{topic_id}.1"


def test_second_manager_of_an_instance_refuses(start_manager: Start, instance: str) -> None:
    first = start_manager(instance)
    client = first.client("ctl")
    client.publish("t", "m/d", 1, 8)
    second = start_manager(instance, runtime=first.runtime, ready=False)
    assert second.proc.wait(WAIT) == 1
    assert second.log().strip() == (
        f"ln_manager: error: instance '{instance}' is already managed by another ln_manager "
        f"(pid {first.proc.pid}, lock {first.runtime / 'manager.lock'})")
    assert len(segments(instance)) == 1  # nothing purged
    assert client.topic_info("t").publishers == 1  # the first one is unaffected
    client.close()


def test_runtime_dir_and_lock(start_manager: Start, instance: str, tmp_path: Path) -> None:
    runtime = tmp_path / "deep" / "run"
    manager = start_manager(instance, runtime=runtime)
    assert stat.S_IMODE(runtime.stat().st_mode) == 0o700
    assert (runtime / "manager.lock").read_text() == f"{manager.proc.pid}\n"
    assert manager.stop() == 0
    again = start_manager(instance, runtime=runtime)  # the lock went with the process
    assert again.stop() == 0


def test_port_in_use(start_manager: Start, instance: str) -> None:
    first = start_manager(instance)
    second = start_manager(unique_instance(), "--port", str(first.port), ready=False)
    assert second.proc.wait(WAIT) == 1
    assert f"cannot listen on 127.0.0.1:{first.port}" in second.log()
