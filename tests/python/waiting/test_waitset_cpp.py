"""The C++ waitset (ln/waitset.hpp, through tests/c/tools/waitset_tool_cpp) against a real
manager: data callbacks see samples in order, a timer keeps its absolute schedule (skipping,
never bursting, when it falls behind), a destroyed attachment gets no more callbacks (also
one destroyed by its own callback), stop() ends spin() from another thread and from a signal
handler, an exception from a callback loses no event, dispatching allocates nothing, and a
requests callback answers service calls."""

from __future__ import annotations

import signal
import uuid
from collections.abc import Callable

import pytest
from topics.conftest import REPO, manager  # noqa: F401 - the fixture cpp_lab uses

import links_and_nodes as ln

from .cpp_fixtures import LIMIT, CppLab, cpp_lab_fixture  # noqa: F401 - fixture

ln.add_message_definition_dir(REPO / "tests" / "fixtures" / "md" / "services")


def unique(name: str) -> str:
    return f"{name}.{uuid.uuid4().hex[:8]}"


def publish(clnt: ln.client, topic: str) -> Callable[[int], None]:
    """A writer of robot/joint_state samples on `topic` with the given cycle."""
    port = clnt.publish(topic, "robot/joint_state")

    def write(cycle: int) -> None:
        port.packet.cycle = cycle
        port.packet.timestamp = cycle * 0.001
        port.write()

    return write


def test_data_callbacks_see_samples_in_order(cpp_lab: CppLab) -> None:
    topic = unique("ws.data")
    tool = cpp_lab.start("data", topic, "20")
    with cpp_lab.client("ws_pub") as clnt:
        write = publish(clnt, topic)
        for cycle in range(1, 21):
            write(cycle)
        code, out = tool.finish()
    assert code == 0, out
    samples = [int(line.split()[1]) for line in out if line.startswith("sample ")]
    assert samples == list(range(1, 21)), out
    callbacks = int(out[-1].removeprefix("callbacks "))
    assert 1 <= callbacks <= 20, out


def test_timer_keeps_its_absolute_schedule(cpp_lab: CppLab) -> None:
    tool = cpp_lab.start("timer", "20", "8")  # 20 ms, 8 callbacks; the third sleeps 70 ms
    first, period = (int(x) for x in tool.lines[0].split()[1:])
    assert tool.lines[1] == f"next_due {first}", tool.lines
    code, out = tool.finish()
    assert code == 0, out
    ticks = [tuple(int(x) for x in line.split()[1:]) for line in out]
    assert len(ticks) == 8, out
    expiries = 0
    for count, at in ticks:
        assert count >= 1, out
        expiries += count
        # never before its expiry on the grid first + k * period
        assert at >= first + (expiries - 1) * period, (expiries, out)
    # the 3.5 periods the third callback slept come as one callback (skip), not three (burst)
    assert ticks[3][0] >= 3, out


def test_destroyed_attachment_gets_no_callbacks(cpp_lab: CppLab) -> None:
    a, b = unique("ws.a"), unique("ws.b")
    tool = cpp_lab.start("detach", a, b)
    with cpp_lab.client("ws_pub") as clnt:
        write_a, write_b = publish(clnt, a), publish(clnt, b)
        write_a(1)
        write_b(1)
        seen: set[str] = set()
        while not {"a 1", "b 1"} <= seen:
            seen.add(tool.next_line())
        tool.send("detach-b")  # destroyed from another thread
        tool.until("^detached b$")
        for cycle in (2, 3):
            write_a(cycle)
            write_b(cycle)
        after = tool.until("^a 3$")
        tool.send("unread-b")  # the samples did reach b's port
        after += tool.until("^b unread")
        assert after[-1] == "b unread 2 3", after
        code, rest = tool.finish()
    assert code == 0, rest
    after += rest
    assert not [line for line in after if line.startswith("b ") and "unread" not in line], after
    assert "self-detaching timer fired 1" in rest, rest


@pytest.mark.parametrize("by", ["stop-thread", "stop-signal"])
def test_stop_ends_spin(cpp_lab: CppLab, by: str) -> None:
    tool = cpp_lab.start(by)
    tool.until("^spinning$")  # spin() runs its callbacks
    if by == "stop-thread":
        tool.send("stop")  # the tool's other thread calls stop()
    else:
        tool.proc.send_signal(signal.SIGTERM)  # its handler calls stop()
    assert tool.next_line() == "stopped"
    assert tool.finish() == (0, [])


def test_an_exception_loses_no_event(cpp_lab: CppLab) -> None:
    """Two timers due at once whose callbacks throw: the first exception leaves spin_once,
    the next spin_once dispatches the other event without waiting for a new one."""
    tool = cpp_lab.start("throw")
    code, out = tool.finish()
    assert code == 0, out
    assert sorted(out[:2]) == ["caught timer a", "caught timer b"], out
    assert out[2:] == ["then 0"], out


def test_dispatch_allocates_nothing(cpp_lab: CppLab) -> None:
    """Timer and descriptor callbacks given as std::function (too big for its inline buffer),
    50 rounds: no operator new while spin() dispatches them."""
    tool = cpp_lab.start("allocs", "50")
    code, out = tool.finish()
    assert code == 0, out
    assert out[0].split()[:2] == ["allocations", "0"], out
    assert out[0].endswith(" reads 50"), out


@pytest.mark.parametrize("attached", ["group", "provider"])
def test_requests_callback_answers_calls(cpp_lab: CppLab, attached: str) -> None:
    name = unique("ws.echo")
    tool = cpp_lab.start("serve", name, *(["provider"] if attached == "provider" else []))
    with cpp_lab.client("ws_caller") as clnt:
        svc = clnt.get_service(name, "lntest/echo")
        for seq in range(3):
            svc.req.caller = 7
            svc.req.seq = seq
            svc.req.text = f"call {seq}"
            resp = svc.call(timeout=LIMIT)
            assert resp.to_dict() == {"caller": 7, "seq": seq, "text": f"call {seq}"}
    code, out = tool.finish()
    assert code == 0, out
    assert sum(int(line.removeprefix("handled ")) for line in out) == 3, out
