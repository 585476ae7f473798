"""ln.WaitSet from Python against a real manager: data, deadline and liveliness of
subscribers, service requests, parameter overrides, descriptors, timers and trigger();
detaching (also by closing what is attached); close() and Ctrl-C ending a blocked wait; and
blocking reads that sleep in one wait (no 0.1 s slices) yet end at once on Ctrl-C or on
close() from another thread."""

from __future__ import annotations

import os
import selectors
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from polling import sigint_default, wait_for
from topics.conftest import Manager

import links_and_nodes as ln
from links_and_nodes.tools.scripting import connect

REPO = Path(__file__).resolve().parents[3]
LIMIT = 60.0  # seconds: an upper bound against hangs, never a pass criterion
MD = "robot/joint_state"
PYTHONPATH = os.pathsep.join([str(REPO / "python"), str(REPO)])

ln.add_message_definition_dir(REPO / "tests" / "fixtures" / "md" / "services")


def kinds(events: list[ln.WaitEvent]) -> list[ln.WaitKind]:
    return [event.kind for event in events]


def next_events(ws: ln.WaitSet) -> list[ln.WaitEvent]:
    """The next non-empty report of `ws` (failing after LIMIT)."""
    events = ws.wait(LIMIT)
    assert events, f"nothing reported within {LIMIT} s"
    return events


def test_data_is_reported_while_samples_are_unread(manager: Manager) -> None:
    with manager.client() as clnt, ln.WaitSet() as ws:
        sub = clnt.subscribe("w.data", MD, buffers=8)
        pub = clnt.publish("w.data", MD)
        state = ws.attach(sub, user="state")
        assert state.what == "subscriber" and state.obj is sub and state.data == "state"
        assert ws.wait(0) == []
        for cycle in (1, 2, 3):
            pub.packet.cycle = cycle
            pub.write()
        events = next_events(ws)
        assert kinds(events) == [ln.WaitKind.DATA]
        assert events[0].attachment is state and events[0].obj is sub
        assert kinds(ws.wait(0)) == [ln.WaitKind.DATA]  # level-triggered: still unread
        assert [sub.read(timeout=0).cycle for _ in range(3)] == [1, 2, 3]
        assert ws.wait(0) == []
        pub.packet.cycle = 4
        pub.write()
        assert kinds(next_events(ws)) == [ln.WaitKind.DATA]
        state.detach()
        assert not state.attached and ws.attachments == []
        assert ws.wait(0) == []  # the unread sample is no longer reported


def test_deadline_fires_without_samples_and_restarts_with_one(manager: Manager) -> None:
    with manager.client() as clnt, ln.WaitSet() as ws:
        sub = clnt.subscribe("w.deadline", MD, buffers=4)
        pub = clnt.publish("w.deadline", MD)
        attachment = ws.attach_subscriber(sub, deadline=0.05)
        events = next_events(ws)
        assert kinds(events) == [ln.WaitKind.DEADLINE] and events[0].count >= 1
        attachment.set_deadline(None)  # none any more: only the sample is reported
        pub.write()
        assert kinds(next_events(ws)) == [ln.WaitKind.DATA]
        assert sub.read(timeout=0) is not None
        assert ws.wait(0) == []
        attachment.set_deadline(0.05)
        events = next_events(ws)
        assert kinds(events) == [ln.WaitKind.DEADLINE]


def test_liveliness_reports_gone_and_back(manager: Manager) -> None:
    with manager.client() as clnt, ln.WaitSet() as ws:
        sub = clnt.subscribe("w.alive", MD)
        ws.attach(sub, data=False, liveliness=True)
        seen: list[ln.WaitKind] = []
        for _ in range(2):
            pub = clnt.publish("w.alive", MD)
            seen += kinds(next_events(ws))
            assert sub.publisher_count == 1
            pub.write()  # data is not asked for: not reported
            pub.close()
            seen += kinds(next_events(ws))
            assert sub.publisher_count == 0
        assert seen == [ln.WaitKind.BACK, ln.WaitKind.GONE] * 2


def test_requests_of_a_provider_are_reported(manager: Manager) -> None:
    with manager.client("provider") as clnt, manager.client("caller") as caller, \
            ln.WaitSet() as ws:
        def echo(request: ln.service_request) -> None:
            request.respond({"seq": request.req.seq + 1, "text": request.req.text})

        provider = clnt.get_service_provider("w.echo", "lntest/echo", echo, group="w")
        ws.attach(provider)
        assert ws.wait(0) == []
        svc = caller.get_service("w.echo", "lntest/echo")
        svc.req.seq = 41
        svc.req.text = "hi"
        answers: list[object] = []
        thread = threading.Thread(target=lambda: answers.append(svc.call(timeout=LIMIT).seq))
        thread.start()
        handled = 0
        while not handled:  # the caller's connection comes first, then its request
            events = next_events(ws)
            assert kinds(events) == [ln.WaitKind.REQUESTS] and events[0].obj is provider
            handled = clnt.wait_and_handle_service_group_requests("w", 0)
        assert handled == 1
        thread.join(LIMIT)
        assert answers == [42]
        assert ws.wait(0) == []


def test_parameter_overrides_are_reported(manager: Manager) -> None:
    with manager.client("pyblk") as clnt, ln.WaitSet() as ws:
        blk = clnt.get_parameter_block("blk")
        blk.add("speed", "double", default=0.5)
        blk.register()
        ws.attach(blk)
        assert ws.wait(0) == []
        script = connect(manager.address, timeout=LIMIT)
        try:
            script.param_set("pyblk.blk", {"speed": 1.25})
        finally:
            script.close()
        events = next_events(ws)
        assert kinds(events) == [ln.WaitKind.PARAMETERS] and events[0].obj is blk
        assert blk.update() == 1 and blk["speed"] == 1.25
        blk.close()  # its attachment ends with it
        assert ws.attachments == []


def test_descriptors_timers_and_trigger() -> None:
    read_end, write_end = os.pipe()
    with open(read_end, "rb", buffering=0) as reader, ln.WaitSet() as ws:
        pipe = ws.attach(reader)
        with pytest.raises(ValueError, match="reading, writing"):
            ws.attach_fd(write_end, readable=False)
        assert ws.wait(0) == []
        os.write(write_end, b"x")
        events = next_events(ws)
        assert kinds(events) == [ln.WaitKind.FD] and events[0].obj is reader
        assert events[0].events == ln.FdEvents.READABLE
        assert kinds(ws.wait(0)) == [ln.WaitKind.FD]  # level-triggered
        assert reader.read(1) == b"x"
        pipe.detach()

        once = ws.attach_timer(0, delay=0.01, user="once")
        events = next_events(ws)
        assert kinds(events) == [ln.WaitKind.TIMER] and events[0].attachment is once
        assert events[0].count == 1
        periodic = ws.attach_timer(0.01)
        assert ws.next_due() is not None
        assert kinds(next_events(ws)) == [ln.WaitKind.TIMER]
        periodic.detach()
        once.detach()
        assert ws.next_due() is None

        threading.Thread(target=ws.trigger).start()
        events = next_events(ws)
        assert kinds(events) == [ln.WaitKind.TRIGGER]
        assert events[0].attachment is None and events[0].count == 1
        ws.trigger()
        ws.trigger()
        assert [(e.kind, e.count) for e in ws.wait(0)] == [(ln.WaitKind.TRIGGER, 2)]
    os.close(write_end)


def test_closing_what_is_attached_detaches_it(manager: Manager) -> None:
    with ln.WaitSet() as ws:
        clnt = manager.client()
        sub = clnt.subscribe("w.close", MD)
        other = clnt.subscribe("w.close2", MD)
        ws.attach(sub)
        ws.attach(other, liveliness=True)
        sub.close()
        assert [a.obj for a in ws.attachments] == [other]
        clnt.close()  # the client closes its ports
        assert ws.attachments == []
        assert ws.wait(0) == []
    assert ws.closed
    with pytest.raises(ValueError, match="closed"):
        ws.wait(0)


def test_close_wakes_a_wait_in_another_thread() -> None:
    ws = ln.WaitSet()
    outcome: list[object] = []

    def wait() -> None:
        try:
            outcome.append(ws.wait(None))
        except BaseException as exc:  # noqa: BLE001 - checked below
            outcome.append(exc)

    thread = threading.Thread(target=wait)
    thread.start()
    wait_for(lambda: ws._waiter is not None, "the wait to start")
    with pytest.raises(ln.LnBusyError):
        ws.wait(0)  # one thread at a time
    ws.close()
    thread.join(LIMIT)
    assert not thread.is_alive()
    assert len(outcome) == 1 and isinstance(outcome[0], ValueError), outcome


def test_bad_arguments() -> None:
    with ln.WaitSet() as ws:
        with pytest.raises(TypeError, match="cannot wait on str"):
            ws.attach("topic")
        with pytest.raises(ValueError, match="at least 0"):
            ws.attach_timer(-1)
        with pytest.raises(ValueError, match="needs a delay"):
            ws.attach_timer(0)
        with pytest.raises(ValueError, match="file descriptor"):
            ws.attach_fd(-3)
        with pytest.raises(ln.LnInvalError):
            ws.wait(float("nan"))
    with pytest.raises(ValueError, match="capacity"):
        ln.WaitSet(capacity=0)


# ---- blocking waits: one kernel wait, ended by Ctrl-C or close() ---------------------------------
def _thread_state(pid: int, tid: int) -> tuple[str, int]:
    """State letter and voluntary context switches of thread `tid` of process `pid`."""
    status = Path(f"/proc/{pid}/task/{tid}/status").read_text()
    fields = dict(line.split(":", 1) for line in status.splitlines() if ":" in line)
    return fields["State"].split()[0], int(fields["voluntary_ctxt_switches"])


def assert_sleeps_in_one_wait(pid: int, tid: int) -> None:
    """The thread is asleep in the kernel and does not wake while nothing happens: a wait
    made of 0.1 s slices would wake a few times in the half second this looks."""
    wait_for(lambda: _thread_state(pid, tid)[0] == "S", "the thread to block")
    before = _thread_state(pid, tid)[1]
    time.sleep(0.5)
    state, after = _thread_state(pid, tid)
    assert state == "S" and after - before <= 1, (state, after - before)


_CHILD = """
import os, sys, threading
import links_and_nodes as ln
clnt = ln.client("child", sys.argv[1])
sub = clnt.subscribe("w.ctrl_c", "robot/joint_state", buffers=4)
pub = clnt.publish("w.ctrl_c", "robot/joint_state")
ws = ln.WaitSet()
ws.attach(sub)
print("ready", threading.get_native_id(), flush=True)
try:
    if sys.argv[2] == "read":
        sub.read(timeout=None)
    else:
        ws.wait(timeout=1e6)
    print("returned")
except KeyboardInterrupt:
    pub.packet.cycle = 7
    pub.write()
    print("interrupted, then", ws.wait(0)[0].kind.name, sub.read(timeout=0).cycle)
ws.close()
clnt.close()
"""


@pytest.mark.parametrize("how", ["read", "wait"])
def test_ctrl_c_ends_a_blocked_read_or_wait(manager: Manager, how: str) -> None:
    env = {**manager.env, "PYTHONPATH": PYTHONPATH}
    child = subprocess.Popen([sys.executable, "-c", _CHILD, manager.address, how],
                             stdout=subprocess.PIPE, text=True, env=env,
                             preexec_fn=sigint_default)
    manager.tools.append(child)
    assert child.stdout is not None
    with selectors.DefaultSelector() as sel:
        sel.register(child.stdout, selectors.EVENT_READ)
        assert sel.select(timeout=LIMIT), f"the child did not start within {LIMIT} s"
    ready = child.stdout.readline().split()
    assert ready[:1] == ["ready"], ready
    assert_sleeps_in_one_wait(child.pid, int(ready[1]))
    child.send_signal(signal.SIGINT)
    try:
        out, _ = child.communicate(timeout=LIMIT)
    except subprocess.TimeoutExpired:
        pytest.fail("Ctrl-C did not end the blocked call")
    assert out.strip() == "interrupted, then DATA 7"
    assert child.returncode == 0


def test_close_from_another_thread_wakes_a_blocked_read(manager: Manager) -> None:
    with manager.client() as clnt:
        sub = clnt.subscribe("w.blocked", MD)
        tid: list[int] = []
        outcome: list[object] = []

        def read() -> None:
            tid.append(threading.get_native_id())
            try:
                outcome.append(sub.read(timeout=1e6))
            except BaseException as exc:  # noqa: BLE001 - checked below
                outcome.append(exc)

        reader = threading.Thread(target=read, daemon=True)
        reader.start()
        wait_for(lambda: tid, "the reader to start")
        assert_sleeps_in_one_wait(os.getpid(), tid[0])
        with pytest.raises(ln.LnBusyError):
            sub.read(timeout=0)  # the reader is inside its call all the time
        sub.close()
        reader.join(LIMIT)
        assert not reader.is_alive(), "the read still blocks after close()"
        assert len(outcome) == 1 and isinstance(outcome[0], ValueError), outcome


def test_a_timed_read_after_a_signal_waits_only_the_rest(manager: Manager) -> None:
    """A signal whose handler returns lets the read go on; it still ends by its timeout."""
    if threading.current_thread() is not threading.main_thread():
        pytest.fail("this test needs the main thread (signal handlers)")
    seen: list[int] = []
    previous = signal.signal(signal.SIGUSR1, lambda signum, frame: seen.append(signum))
    try:
        with manager.client() as clnt:
            sub = clnt.subscribe("w.timed", MD)
            timer = threading.Timer(0.05, signal.pthread_kill,
                                    (threading.main_thread().ident, signal.SIGUSR1))
            timer.start()
            assert sub.read(timeout=0.3) is None
            timer.join(LIMIT)
            assert seen == [signal.SIGUSR1]
    finally:
        signal.signal(signal.SIGUSR1, previous)
