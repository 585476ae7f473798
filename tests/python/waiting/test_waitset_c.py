"""The C waitset (tests/c/tools/waitset_tool.c) against a real manager: exact event sequences
for data, deadline and liveliness (a publisher SIGKILLed is "gone", a new one "back"), timers
on an absolute schedule, 200 attached inports, attach/detach from another thread, bad input,
and nothing left in /dev/shm by a waitset process that is SIGKILLed."""

from __future__ import annotations

import os
import queue
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from topics.conftest import TOOLS, Manager

from links_and_nodes.naming import parse_segment_name, sanitize_instance

WAITSET_TOOL = TOOLS / "waitset_tool"
LIMIT = 60.0  # seconds: an upper bound against hangs, never a pass criterion


def tool(mgr: Manager, *args: str) -> subprocess.Popen[str]:
    if not WAITSET_TOOL.exists():
        pytest.fail(f"{WAITSET_TOOL} is missing: run scons first")
    proc = subprocess.Popen([str(WAITSET_TOOL), *args], stdout=subprocess.PIPE, text=True,
                            env=mgr.env)
    mgr.tools.append(proc)
    return proc


_readers: dict[int, queue.Queue[str]] = {}


def next_line(proc: subprocess.Popen[str], limit: float = LIMIT) -> str:
    """The tool's next line (waiting at most `limit` s, an upper bound against hangs); a
    thread per process reads them, so lines that came together are not lost in a buffer."""
    lines = _readers.get(proc.pid)
    if lines is None:
        lines = _readers[proc.pid] = queue.Queue()
        stream = proc.stdout
        assert stream is not None

        def pump(q: queue.Queue[str] = lines) -> None:
            for line in stream:
                q.put(line.strip())
            q.put("<eof>")

        threading.Thread(target=pump, daemon=True).start()
    try:
        return lines.get(timeout=limit)
    except queue.Empty:
        proc.kill()
        pytest.fail(f"no line from the tool within {limit} s")


def wait_ready(proc: subprocess.Popen[str]) -> None:
    line = next_line(proc)
    assert line == "ready", f"tool did not start: {line!r}, exit {proc.poll()}"


def publisher_process(mgr: Manager, topic: str, values: str) -> subprocess.Popen[str]:
    """A Python publisher of lntest/pattern samples holding each of `values` (comma list,
    "loop": forever), printing "ready" once it is registered and "sent" after the list."""
    code = f"""
import sys, time
import links_and_nodes as ln
ln.add_message_definition_dir({str(TOOLS.parents[4] / 'tests' / 'fixtures' / 'md' / 'topics')!r})
clnt = ln.client("waitset_pub", {mgr.address!r})
pub = clnt.publish({topic!r}, "lntest/pattern")
print("ready", flush=True)
values = {values!r}
if values == "loop":
    while True:
        time.sleep(1)
for v in values.split(","):
    pub.packet.word[0] = int(v)
    pub.write()
print("sent", flush=True)
sys.stdin.readline()
"""
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE,
                            stdin=subprocess.PIPE, text=True, env=mgr.env)
    mgr.tools.append(proc)
    return proc


def test_data_and_liveliness_in_exact_order(manager: Manager) -> None:
    watcher = tool(manager, "watch", "ws.live", "0", str(LIMIT))
    wait_ready(watcher)
    pub = publisher_process(manager, "ws.live", "1,2,3")
    wait_ready(pub)
    assert next_line(pub) == "sent"
    lines = [next_line(watcher) for _ in range(4)]
    # the publisher registered before it wrote: "back", then every sample in order
    assert lines == ["back", "data 1", "data 2", "data 3"]
    pub.kill()  # SIGKILL: the manager sees the connection end and counts it gone
    pub.wait()
    assert next_line(watcher) == "gone"
    again = publisher_process(manager, "ws.live", "4,0")
    wait_ready(again)
    assert [next_line(watcher) for _ in range(4)] == ["back", "data 4", "data 0", "end"]
    assert watcher.wait(timeout=LIMIT) == 0
    again.kill()
    again.wait()


def test_deadline_fires_while_silent_and_rearms_on_samples(manager: Manager) -> None:
    with manager.client("ws_deadline") as clnt:
        pub = clnt.publish("ws.deadline", "lntest/pattern")
        watcher = tool(manager, "watch", "ws.deadline", "0.2", str(LIMIT))
        wait_ready(watcher)
        first = next_line(watcher)
        assert first.startswith("deadline "), first  # nothing for 0.2 s after the attach
        assert int(first.split()[1]) >= 1
        pub.packet.word[0] = 5
        pub.write()
        line = next_line(watcher)
        while line.startswith("deadline"):  # those that fell due before the sample came
            line = next_line(watcher)
        assert line == "data 5"
        assert next_line(watcher).startswith("deadline ")  # silent again: it fires again
        pub.packet.word[0] = 0
        pub.write()
        line = next_line(watcher)
        while line.startswith("deadline"):
            line = next_line(watcher)
        assert (line, next_line(watcher)) == ("data 0", "end")
        assert watcher.wait(timeout=LIMIT) == 0


def test_timer_keeps_an_absolute_schedule() -> None:
    if not WAITSET_TOOL.exists():
        pytest.fail(f"{WAITSET_TOOL} is missing: run scons first")
    out = subprocess.run([str(WAITSET_TOOL), "timer", "20", "25"], capture_output=True,
                         text=True, timeout=LIMIT, check=True).stdout.split("\n")
    ticks = [line.split() for line in out if line.startswith("tick")]
    assert out[len(ticks)] == "done"
    assert sum(int(t[1]) for t in ticks) >= 25
    # never before its expiry: lateness is measured against first + k * period
    assert all(int(t[2]) >= 0 for t in ticks), ticks


def test_hundreds_of_inports_one_active(manager: Manager) -> None:
    n = 200
    watcher = tool(manager, "many", "ws.many", str(n))
    wait_ready(watcher)
    with manager.client("ws_many_pub") as clnt:
        pubs = {i: clnt.publish(f"ws.many.{i}", "lntest/pattern") for i in (0, 77, n - 1)}
        for value, i in ((11, 77), (12, 0), (13, n - 1), (0, 77)):
            pubs[i].packet.word[0] = value
            pubs[i].write()
            time.sleep(0.01)  # one at a time, so the order of the lines is the order sent
        lines = [next_line(watcher) for _ in range(5)]
    assert lines == ["77 data 11", "0 data 12", f"{n - 1} data 13", "77 data 0", "end"]
    assert watcher.wait(timeout=LIMIT) == 0


def test_attach_and_detach_from_another_thread(manager: Manager) -> None:
    with manager.client("ws_race_pub") as clnt:
        pub = clnt.publish("ws.race", "lntest/pattern")
        racer = tool(manager, "race", "2", "ws.race")
        end = time.monotonic() + 2
        while time.monotonic() < end:
            pub.packet.word[0] = 1
            pub.write()
            time.sleep(0.0005)
        assert racer.wait(timeout=LIMIT) == 0
        line = next_line(racer)
        while line.startswith("#"):  # the samples it read meanwhile
            line = next_line(racer)
        assert line.startswith("ok ")


BAD_WITHOUT_MANAGER = {
    "create_null": "EINVAL", "wait_null_array": "EINVAL", "wait_zero_size": "EINVAL",
    "wait_nan": "EINVAL", "wait_negative_poll": "OK", "attach_null_inport": "EBADHANDLE",
    "attach_bad_fd": "EINVAL", "attach_closed_fd": "ESYS", "attach_no_events": "EINVAL",
    "timer_negative": "EINVAL", "timer_never": "EINVAL", "detach_unknown": "ENOTFOUND",
    "deadline_unknown": "ENOTFOUND", "group_null_client": "EBADHANDLE",
    "provider_null": "EBADHANDLE", "params_null": "EBADHANDLE", "trigger_null": "EBADHANDLE",
    "destroy": "OK"}


def test_bad_input_gets_codes_not_crashes() -> None:
    if not WAITSET_TOOL.exists():
        pytest.fail(f"{WAITSET_TOOL} is missing: run scons first")
    out = subprocess.run([str(WAITSET_TOOL), "bad"], capture_output=True, text=True,
                         timeout=LIMIT, check=True).stdout
    assert dict(line.split() for line in out.splitlines()) == BAD_WITHOUT_MANAGER


def test_bad_input_on_a_real_inport(manager: Manager) -> None:
    proc = tool(manager, "bad", "ws.bad")
    assert proc.wait(timeout=LIMIT) == 0
    assert proc.stdout is not None
    got = dict(line.split() for line in proc.stdout.read().splitlines())
    assert got == {**BAD_WITHOUT_MANAGER, "attach_negative_deadline": "EINVAL",
                   "attach_nan_deadline": "EINVAL", "attach_bad_flags": "EINVAL",
                   "attach_inport": "OK", "attach_inport_twice": "EBUSY",
                   "attach_inport_elsewhere": "EBUSY", "group_none": "ENOTFOUND"}


def shm_names(instance: str) -> set[str]:
    return {p.name for p in Path("/dev/shm").iterdir() if instance in p.name}


def test_a_killed_waitset_leaves_nothing_and_publishers_go_on(manager: Manager) -> None:
    with manager.client("ws_kill_pub") as clnt:
        pub = clnt.publish("ws.kill", "lntest/pattern")
        before = shm_names(sanitize_instance(manager.instance))
        watcher = tool(manager, "watch", "ws.kill", "0", str(LIMIT))
        wait_ready(watcher)
        pub.packet.word[0] = 1
        pub.write()
        assert next_line(watcher) == "data 1"
        os.kill(watcher.pid, signal.SIGKILL)
        watcher.wait()
        for value in range(2, 200):  # the bell it left in the ring is refused, harmlessly
            pub.packet.word[0] = value
            pub.write()
        sub = clnt.subscribe("ws.kill", "lntest/pattern")
        pub.packet.word[0] = 500
        pub.write()
        assert sub.read(timeout=LIMIT) is not None
        assert sub.packet.word[0] == 500
        sub.close()
        # the topic's ring (grown for the watcher's 16 buffers) and nothing else: a waitset
        # makes no segment (its bell is an abstract socket, gone with its process); the
        # manager fixture checks at the end that no segment of the instance is left at all
        instance = sanitize_instance(manager.instance)
        after = shm_names(instance)
        assert before <= after and after, (before, after)
        assert all(parse_segment_name(instance, name) for name in after), after
