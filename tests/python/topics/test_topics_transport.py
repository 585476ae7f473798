"""Topics across hosts, as far as one host can show it: the transport a subscriber asks for
(Python's transport=, the C++ wrapper's flags) reaches the manager, and samples a daemon
injects through a ring tap reach real subscribers with their original sequence numbers and
timestamps, across gaps and across the ring growing under them."""

from __future__ import annotations

import ctypes
import re

import pytest

import links_and_nodes as ln
from links_and_nodes import _adminlib

from .conftest import Manager, wait_ready

MD = "robot/joint_state"


def port_lines(manager: Manager, topic: str) -> list[tuple[str, str]]:
    """(kind, transport note) of each port the manager opened on `topic`, in order."""
    log = manager.process.log.read_text(errors="replace")
    return re.findall(rf"(publisher|subscriber) '{re.escape(topic)}' -> port \d+, \S+"
                      r"(?: reader \d+)?(.*)", log)


@pytest.mark.parametrize("transport", ["quic", "UDP", "", 1])
def test_transport_must_be_udp_tcp_or_none(manager: Manager, transport: object) -> None:
    with manager.client() as clnt:
        with pytest.raises(ValueError, match="transport must be None, 'udp' or 'tcp'"):
            clnt.subscribe("t.transport", MD, transport=transport)  # type: ignore[arg-type]
        assert port_lines(manager, "t.transport") == []  # nothing reached the manager
        sub = clnt.subscribe("t.transport", MD, transport="udp")
        assert sub.transport == "udp"


def test_transport_reaches_the_manager(manager: Manager) -> None:
    with manager.client() as clnt:
        pub = clnt.publish("t.via", MD)
        tcp = clnt.subscribe("t.via", MD, buffers=4, transport="tcp")
        udp = clnt.subscribe("t.via", MD, transport="udp")
        default = clnt.subscribe("t.via", MD)
        assert port_lines(manager, "t.via") == [
            ("publisher", ""), ("subscriber", ", transport tcp"),
            ("subscriber", ", transport udp"), ("subscriber", "")]
        # on one host the flag changes nothing: shared memory as always
        pub.packet.cycle = 7
        pub.write()
        for sub in (tcp, udp, default):
            pkt = sub.read(timeout=30)
            assert pkt is not None and pkt.cycle == 7


def test_cpp_subscriber_passes_its_transport(manager: Manager) -> None:
    sub = manager.tool("sub-joint", "t.cpp", "1", "30", "tcp", cpp=True)
    wait_ready(sub)
    assert port_lines(manager, "t.cpp") == [("subscriber", ", transport tcp")]
    sub.kill()
    sub.wait()


class Tap:
    """A ring tap on one of the manager's segments, as the receiving daemon has it."""

    def __init__(self, segment: str, layout_hash: int, size: int) -> None:
        handle = ctypes.c_void_p()
        _adminlib.ln_ring_tap_open(ctypes.byref(handle), segment.encode(), layout_hash, size,
                                   _adminlib.LN_TAP_EVERY)
        self.handle = handle
        self.size = size

    def inject(self, packet: ctypes.Structure, seq: int, timestamp_ns: int) -> None:
        _adminlib.ln_ring_tap_inject(self.handle, ctypes.byref(packet), seq, timestamp_ns)

    @property
    def segment(self) -> str:
        return _adminlib.ln_ring_tap_segment(self.handle).decode()

    def close(self) -> None:
        _adminlib.ln_ring_tap_close(self.handle)


def test_injected_samples_reach_subscribers(manager: Manager) -> None:
    with manager.client() as clnt:
        queued = clnt.subscribe("t.remote", MD, buffers=8)
        latest = clnt.subscribe("t.remote", MD)
        cls = queued.message_class
        gen1 = f"/ln.{manager.instance}.1.1"
        tap = Tap(gen1, cls.LAYOUT_HASH, ctypes.sizeof(cls))
        sample = cls()
        for seq in (1, 2, 5):  # 3 and 4 were lost on the way
            sample.cycle = seq * 10
            tap.inject(sample, seq, 1_700_000_000_000_000_000 + seq)
        got = []
        while (pkt := queued.read(timeout=0)) is not None:
            got.append((pkt.cycle, queued.info.seq, queued.info.timestamp_ns,
                        queued.info.overruns))
        assert got == [(10, 1, 1_700_000_000_000_000_001, 0),
                       (20, 2, 1_700_000_000_000_000_002, 0),
                       (50, 5, 1_700_000_000_000_000_005, 2)]
        pkt = latest.read(timeout=0)
        assert pkt is not None and (pkt.cycle, latest.info.seq) == (50, 5)
        with pytest.raises(ln.LnOverrunError):
            tap.inject(sample, 5, 0)  # a duplicate changes nothing

        # A deeper subscriber grows the ring: the tap follows it with the next inject.
        deeper = clnt.subscribe("t.remote", MD, buffers=32)
        sample.cycle = 60
        tap.inject(sample, 6, 1_700_000_000_000_000_006)
        assert tap.segment == f"/ln.{manager.instance}.1.2"
        for sub in (queued, latest, deeper):
            pkt = sub.read(timeout=30)
            assert pkt is not None and (pkt.cycle, sub.info.seq) == (60, 6)
            assert sub.info.timestamp_ns == 1_700_000_000_000_000_006
        assert queued.overruns == 2
        tap.close()
