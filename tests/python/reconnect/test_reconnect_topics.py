"""A manager SIGKILLed and started again under running clients (docs/manager.md, "A manager
restarted under running clients"): old and new ports of a topic share its adopted ring,
sequence numbers go on, a client that only writes is registered again by itself, what
nobody takes back goes after the adoption window, a manager killed during the
re-registration is survived, and destroy does not wait for a manager that is away."""

from __future__ import annotations

import ctypes

import pytest
from polling import wait_for

import links_and_nodes as ln
from links_and_nodes import _adminlib
from links_and_nodes.manager.frontends.launch import segments

from .conftest import LIMIT, Restarts, read_until

MARK = 0xFFFFFFF0  # a cycle the C publisher never reaches in a test


def test_old_and_new_ports_share_the_adopted_ring(restarts: Restarts) -> None:
    """C publisher and Python subscriber across the restart; a new subscriber gets the old
    publisher's samples, the old subscriber a new publisher's, on the same segments."""
    restarts.tool("topic_tool", "pub-loop", "rc.state", "2000")
    old = restarts.client("old").subscribe("rc.state", "robot/joint_state", buffers=64)
    _, before = read_until(old, lambda p: p.cycle > 1, "samples before the restart")
    rings = segments(restarts.instance)

    restarts.restart()
    fresh = restarts.client("fresh")
    sub = fresh.subscribe("rc.state", "robot/joint_state", buffers=64)
    pkt, seqs = read_until(sub, lambda p: 0 < p.cycle < MARK, "the old publisher's samples")
    assert seqs[0] > before[-1]  # the topic's sequence numbers went on
    pub = fresh.publish("rc.state", "robot/joint_state")
    pub.packet.cycle = MARK
    pub.write()
    _, after = read_until(old, lambda p: p.cycle == MARK, "the new publisher's sample")
    numbers = before + after
    assert numbers == sorted(set(numbers))  # strictly increasing: one count, no restart
    assert segments(restarts.instance) == rings  # nothing new was made
    wait_for(lambda: restarts.topics()["rc.state"]["publishers"] == 2
             and restarts.topics()["rc.state"]["subscribers"] == 2, "all four ports known")
    assert "took back subscriber 'rc.state'" in restarts.log()
    assert "took back publisher 'rc.state'" in restarts.log()
    assert sub.publisher_count == 2 and pub.subscriber_count == 2  # the header's counts


def test_client_that_only_writes_is_registered_again(restarts: Restarts) -> None:
    restarts.tool("topic_tool", "pub-loop", "rc.loop", "5000")
    restarts.restart()
    wait_for(lambda: restarts.topics().get("rc.loop", {}).get("publishers") == 1,
             "the writing client's publisher back in the registry")
    log = restarts.log()
    assert "client topic_tool" in log and "reconnected" in log


def test_what_nobody_takes_back_goes_after_the_window(restarts: Restarts) -> None:
    """A subscriber process killed while the manager is away: its reader slot is freed and
    its own topic removed once the window is over; nothing is left at the end."""
    restarts.window = 1.0
    restarts.tool("topic_tool", "pub-loop", "rc.kept", "5000")
    victim = restarts.python(
        "import links_and_nodes as ln, sys\n"
        "c = ln.client('victim')\n"
        "s = c.subscribe('rc.kept', 'robot/joint_state', buffers=4)\n"
        "p = c.publish('rc.own', 'robot/joint_state')\n"
        "print('ready', flush=True)\n"
        "sys.stdin.readline()\n")
    assert victim.stdout is not None
    assert victim.stdout.readline().strip() == "ready"
    restarts.kill()
    victim.kill()
    victim.wait()
    restarts.start()
    restarts.wait_log("adopted topic 'rc.own' was not taken back: removed")
    restarts.wait_log("topic 'rc.kept': released reader slot 0 of subscribers that did not "
                      "come back")
    kept = segments(restarts.instance)  # rc.kept's generations (it grew for the subscriber)
    assert kept and all(n.startswith(f"ln.{restarts.instance}.1.") for n in kept)
    newest = max(kept, key=lambda n: int(n.rsplit(".", 1)[1]))
    handle = _adminlib.RingAdminHandle()
    _adminlib.ln_ring_admin_open(ctypes.byref(handle), f"/{newest}".encode())
    info = _adminlib.RingInfo()
    _adminlib.ln_ring_admin_info(handle, ctypes.byref(info))
    _adminlib.ln_ring_admin_close(handle)
    assert info.topic == b"rc.kept"
    assert info.active_readers == 0  # the dead subscriber's slot is free again
    assert (info.publishers, info.subscribers) == (1, 0)


def test_manager_killed_during_reregistration(restarts: Restarts) -> None:
    clnt = restarts.client("many")
    pubs = [clnt.publish(f"rc.many.{i}", "robot/joint_state") for i in range(150)]
    restarts.restart()
    restarts.wait_log("took back publisher")  # the re-registration has begun ...
    restarts.restart()  # ... and its manager is killed again
    wait_for(lambda: sum(t["publishers"] for t in restarts.topics().values()) == len(pubs),
             "every publisher back with the third manager")
    sub = restarts.client("reader").subscribe("rc.many.7", "robot/joint_state")
    pubs[7].packet.cycle = 77
    pubs[7].write()
    pkt, _ = read_until(sub, lambda p: p.cycle == 77, "a sample on a re-registered port")
    assert pkt.cycle == 77


def test_calls_fail_while_the_manager_is_away_and_work_after(restarts: Restarts) -> None:
    clnt = restarts.client("calls", timeout=LIMIT)
    restarts.kill()
    with pytest.raises(ln.LnConnectionError):
        clnt.publish("rc.x", "robot/joint_state")
    restarts.start()
    pub = wait_for(lambda: _try_publish(clnt), "publishing again after the restart")
    assert pub is not None


def _try_publish(clnt: ln.client) -> object:
    try:
        return clnt.publish("rc.x", "robot/joint_state")
    except ln.LnConnectionError:
        return None


def test_without_reconnection_the_connection_stays_lost(restarts: Restarts) -> None:
    clnt = restarts.client("stays", reconnect=False)
    restarts.restart()
    restarts.client("other").publish("rc.y", "robot/joint_state")  # the new one serves
    with pytest.raises(ln.LnConnectionError):  # finds the connection closed
        clnt.publish("rc.y", "robot/joint_state")
    with pytest.raises(ln.LnConnectionError, match="lost earlier"):  # and never comes back
        clnt.publish("rc.y", "robot/joint_state")


def test_destroy_while_the_manager_is_away(restarts: Restarts) -> None:
    """Destroying a client with ports and a provider while its manager is down (and its
    monitor keeps trying) returns: the process prints "closed" and exits 0."""
    proc = restarts.python(
        "import links_and_nodes as ln, sys\n"
        "ln.add_message_definition_dir(sys.argv[1])\n"
        "c = ln.client('leaving')\n"
        "p = c.publish('rc.z', 'robot/joint_state')\n"
        "s = c.subscribe('rc.z', 'robot/joint_state')\n"
        "v = c.get_service_provider('rc.svc', 'robot/set_gains', lambda r: r.respond())\n"
        "print('ready', flush=True)\n"
        "sys.stdin.readline()\n"
        "c.close()\n"
        "print('closed', flush=True)\n", str(restarts.tmp.parent))
    assert proc.stdout is not None and proc.stdin is not None
    assert proc.stdout.readline().strip() == "ready"
    restarts.kill()
    out, _ = proc.communicate("go\n", timeout=LIMIT)
    assert out.strip() == "closed" and proc.returncode == 0
    restarts.start()  # removes the orphaned ring once the window is over
    wait_for(lambda: segments(restarts.instance) == [], "the orphaned ring removed")
