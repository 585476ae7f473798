"""The Python port objects around libln's: closing (also under a call in another thread),
Ctrl-C during a blocking read, the packet a port reads into and writes from, and the
checks of subscribe/publish arguments."""

from __future__ import annotations

import ctypes
import os
import signal
import subprocess
import sys
import threading
from collections.abc import Callable
from pathlib import Path

import pytest
from polling import sigint_default, wait_for

import links_and_nodes as ln

from .conftest import REPO, Manager, wait_ready

LIMIT = 60.0  # seconds: an upper bound against hangs, never a pass criterion


def _sleeping(tid: int) -> bool:
    """Whether thread `tid` of this process sleeps in the kernel (state S)."""
    stat = Path(f"/proc/self/task/{tid}/stat").read_text()
    return stat.rsplit(")", 1)[1].split()[0] == "S"


def test_ports_used_after_close_raise_value_error(manager: Manager) -> None:
    with manager.client() as clnt:
        pub = clnt.publish("t.closed", "robot/joint_state")
        sub = clnt.subscribe("t.closed", "robot/joint_state")
        pub.close()
        sub.close()
        with pytest.raises(ValueError, match="closed"):
            pub.write()
        with pytest.raises(ValueError, match="closed"):
            sub.read(timeout=0)
        with pytest.raises(ValueError, match="closed"):
            with sub.borrow(timeout=0):
                pass
        pub2 = clnt.publish("t.closed", "robot/joint_state")
        sub2 = clnt.subscribe("t.closed", "robot/joint_state")
    # the client closed them: libln freed the ports, Python must not hand them to it
    with pytest.raises(ValueError, match="closed"):
        pub2.write()
    with pytest.raises(ValueError, match="closed"):
        sub2.read(timeout=0)
    with pytest.raises(ValueError, match="closed"):
        with pub2.loan(timeout=0):
            pass


@pytest.mark.parametrize("close", ["port", "client"])
def test_close_ends_a_blocking_read_in_another_thread(manager: Manager, close: str) -> None:
    clnt = manager.client()
    sub = clnt.subscribe("t.blocked", "robot/joint_state")
    outcome: list[object] = []
    tid: list[int] = []

    def read() -> None:
        tid.append(threading.get_native_id())
        try:
            outcome.append(sub.read(timeout=None))
        except BaseException as exc:  # noqa: BLE001 - checked below
            outcome.append(exc)

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    wait_for(lambda: tid and _sleeping(tid[0]), "the reader to block")
    if close == "port":
        sub.close()
    else:
        clnt.close()
    reader.join(LIMIT)
    assert not reader.is_alive(), "the read still blocks after close()"
    assert len(outcome) == 1 and isinstance(outcome[0], ValueError), outcome
    # a publisher of another client must not wake a reader on freed memory
    with manager.client("other") as other:
        other.publish("t.blocked", "robot/joint_state").write()
    clnt.close()


def test_a_port_in_use_by_another_thread_is_refused(manager: Manager) -> None:
    """libln allows one thread per port at a time; Python refuses a second one with
    LnBusyError instead of letting them race on the port's state."""
    with manager.client() as clnt:
        sub = clnt.subscribe("t.two_threads", "robot/joint_state")
        tid: list[int] = []
        outcome: list[object] = []

        def read() -> None:
            tid.append(threading.get_native_id())
            try:
                outcome.append(sub.read(timeout=None))
            except BaseException as exc:  # noqa: BLE001 - checked below
                outcome.append(exc)

        reader = threading.Thread(target=read, daemon=True)
        reader.start()
        wait_for(lambda: tid and _sleeping(tid[0]), "the reader to block")
        # The blocked read waits in 0.1 s slices; a call that falls between two of them
        # would run: try again then (a few microseconds in 0.1 s).
        def refused(call: Callable[[], object]) -> bool:
            for _ in range(5):
                try:
                    call()
                except ln.LnBusyError as exc:
                    return "another thread" in str(exc)
            return False

        assert refused(lambda: sub.read(timeout=0))
        assert refused(lambda: setattr(sub, "packet", sub.message_class()))
        sub.close()  # ends the blocked read
        reader.join(LIMIT)
        assert not reader.is_alive()
        assert len(outcome) == 1 and isinstance(outcome[0], ValueError), outcome


_CHILD = """
import sys
import links_and_nodes as ln
clnt = ln.client("child", sys.argv[1])
sub = clnt.subscribe("t.ctrl_c", "robot/joint_state", buffers=4)
pub = clnt.publish("t.ctrl_c", "robot/joint_state")
print("ready", flush=True)
try:
    sub.read(timeout=float(sys.argv[2]) if sys.argv[2] != "None" else None)
    print("read returned")
except KeyboardInterrupt:
    pub.packet.cycle = 7
    pub.write()
    print("interrupted, then read cycle", sub.read(timeout=0).cycle)
clnt.close()
"""


@pytest.mark.parametrize("timeout", ["None", "-1", "1e6"])
def test_ctrl_c_ends_a_blocking_read(manager: Manager, timeout: str) -> None:
    env = {**manager.env, "PYTHONPATH": os.pathsep.join([str(REPO / "python"), str(REPO)])}
    child = subprocess.Popen([sys.executable, "-c", _CHILD, manager.address, timeout],
                             stdout=subprocess.PIPE, text=True, env=env,
                             preexec_fn=sigint_default)
    manager.tools.append(child)
    wait_ready(child, LIMIT)
    # the main thread is asleep in the kernel only inside the read
    stat = Path(f"/proc/{child.pid}/stat")
    wait_for(lambda: stat.read_text().rsplit(")", 1)[1].split()[0] == "S",
             "the child to block in read()")
    child.send_signal(signal.SIGINT)
    try:
        out, _ = child.communicate(timeout=LIMIT)
    except subprocess.TimeoutExpired:
        pytest.fail("Ctrl-C did not end a blocking read")
    assert out.strip() == "interrupted, then read cycle 7"
    assert child.returncode == 0


def test_a_replaced_packet_is_the_one_written_and_read(manager: Manager) -> None:
    with manager.client() as clnt:
        pub = clnt.publish("t.packet", "robot/joint_state")
        sub = clnt.subscribe("t.packet", "robot/joint_state", buffers=4)
        sent = pub.message_class()
        sent.cycle = 42
        pub.packet = sent
        pub.write()
        mine = sub.message_class()
        sub.packet = mine
        got = sub.read(timeout=LIMIT)
        assert got is mine and mine.cycle == 42
        with pytest.raises(TypeError, match="robot/joint_state"):
            pub.packet = object()


def test_a_message_of_another_md_is_refused(manager: Manager) -> None:
    with manager.client() as clnt:
        pub = clnt.publish("t.other_md", "ln/time")
        sub = clnt.subscribe("t.other_md", "ln/time", buffers=4)
        other = ln.message_class("ln/string")()
        assert ctypes.sizeof(other) == ctypes.sizeof(pub.message_class)  # libln cannot tell
        with pytest.raises(TypeError, match="ln/time"):
            pub.write(other)
        with pytest.raises(TypeError, match="ln/time"):
            sub.packet = other
        assert sub.read(timeout=0) is None


@pytest.mark.parametrize(("kwargs", "error"), [
    ({"buffers": 2**32 + 4}, ValueError),   # ctypes kept 4 of it
    ({"buffers": -1}, ValueError),
    ({"buffers": 0}, ValueError),
    ({"buffers": 2.5}, TypeError),
    ({"buffers": True}, TypeError),
    ({"spin_us": -1}, ValueError),          # ctypes made it 4294967295 µs
    ({"spin_us": 2**32}, ValueError),
])
def test_subscribe_checks_its_numbers(manager: Manager, kwargs: dict[str, object],
                                      error: type[Exception]) -> None:
    with manager.client() as clnt:
        with pytest.raises(error):
            clnt.subscribe("t.args", "robot/joint_state", **kwargs)  # type: ignore[arg-type]
        assert clnt.subscribe("t.args", "robot/joint_state", buffers=4, spin_us=0).buffers == 4


def test_names_with_nul_are_refused(manager: Manager) -> None:
    with manager.client() as clnt:
        with pytest.raises(ValueError, match="NUL"):
            clnt.publish("t.nul\0tail", "robot/joint_state")  # libln would see "t.nul"
        with pytest.raises(ValueError, match="NUL"):
            clnt.subscribe("t.nul\0tail", "robot/joint_state")
        with pytest.raises(ValueError, match="buffers"):
            clnt.publish("t.nul", "robot/joint_state", buffers=-3)
