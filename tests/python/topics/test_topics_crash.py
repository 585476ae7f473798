"""Crash safety end to end: publishers SIGKILLed mid-write, clients and the manager
SIGKILLed, and what is left in /dev/shm afterwards."""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

from .conftest import Manager, segments, start_manager, wait_ready

FINAL_FIRST = 10**12  # values of the last publisher's samples, never written by the others


def test_publisher_killed_fifty_times(manager: Manager) -> None:
    final_value = FINAL_FIRST + 999
    sub = manager.tool("sub-pattern", "crash", str(10**15), "1", "120", str(final_value))
    wait_ready(sub)
    rng = random.Random(1234)
    for _ in range(50):
        pub = manager.tool("pub-pattern", "crash", "0")
        wait_ready(pub)
        time.sleep(rng.uniform(0.0, 0.02))  # somewhere inside its tight write loop
        pub.send_signal(signal.SIGKILL)
        pub.wait()
        assert pub.stdout is not None
        pub.stdout.close()
    # A new publisher resumes the topic: its last sample must reach the subscriber.
    final = manager.tool("pub-pattern", "crash", "1000", "nowait", str(FINAL_FIRST))
    assert final.wait(timeout=60) == 0
    out, _ = sub.communicate(timeout=180)
    fields = out.split()
    stats = dict(zip(fields[0::2], (int(v) for v in fields[1::2]), strict=True))
    assert sub.returncode == 0
    assert stats["torn"] == 0 and stats["disorder"] == 0
    assert stats["timeouts"] == 0  # it never waited in vain, let alone hung
    assert stats["value"] == final_value


CLIENT = """
import sys, time, links_and_nodes as ln
c = ln.client("victim", sys.argv[1])
pub = c.publish("victim.out", "robot/joint_state")
sub = c.subscribe("victim.in", "robot/joint_state", buffers=8)
pub.write()
print("ready", flush=True)
time.sleep(600)
"""


def test_killed_client_leaves_no_segment(manager: Manager) -> None:
    proc = subprocess.Popen([sys.executable, "-c", CLIENT, manager.address],
                            stdout=subprocess.PIPE, text=True)
    wait_ready(proc)
    assert len(segments(manager.instance)) == 2
    proc.kill()
    proc.wait()
    deadline = time.monotonic() + 30
    while segments(manager.instance) and time.monotonic() < deadline:
        time.sleep(0.02)
    assert segments(manager.instance) == []
    with manager.client() as clnt:  # and the manager keeps serving
        assert clnt.publish("after.kill", "robot/joint_state").subscriber_count == 0


def test_killed_manager_is_cleaned_up_by_the_next_start(manager: Manager,
                                                        tmp_path: Path) -> None:
    proc = subprocess.Popen([sys.executable, "-c", CLIENT, manager.address],
                            stdout=subprocess.PIPE, text=True)
    wait_ready(proc)
    manager.proc.send_signal(signal.SIGKILL)
    manager.proc.wait()
    proc.kill()
    proc.wait()
    assert len(segments(manager.instance)) == 2  # nobody was left to remove them
    # adopted for returning clients, removed once the adoption window passed without one
    again = start_manager(manager.instance, tmp_path / "runtime", "--adopt-window", "0.2")
    try:
        deadline = time.monotonic() + 30
        while segments(manager.instance) and time.monotonic() < deadline:
            time.sleep(0.02)
        assert segments(manager.instance) == []
    finally:
        again.proc.terminate()
        again.proc.wait(timeout=30)
    assert os.path.isdir(tmp_path / "runtime")
