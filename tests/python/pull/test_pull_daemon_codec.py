"""The PULL_* daemon messages of the manager's daemon client against the wire table of
docs/daemon.md (byte strings written out here), and malformed PULL_LIST replies."""

from __future__ import annotations

import struct

import pytest

from links_and_nodes.manager.network import daemon_pull as dp
from links_and_nodes.manager.processes.daemon_wire import Msg


def s(text: bytes) -> bytes:
    return struct.pack("<I", len(text)) + text


def test_message_numbers() -> None:
    assert (Msg.PULL_TOPIC, Msg.PULL_REMOVE, Msg.PULL_STATUS, Msg.PULL_LIST) == \
        (0x51, 0x52, 0x53, 0x2A)


def test_pull_topic_request_bytes() -> None:
    got = dp.encode_pull_topic("arm.state", "ring0", "robot/joint_state", 0x1122334455667788,
                               172, "", 6363, "/ln/lab/arm.state", 64, 1000)
    assert got == (s(b"arm.state") + s(b"ring0") + s(b"robot/joint_state")
                   + bytes.fromhex("8877665544332211") + struct.pack("<Q", 172) + s(b"")
                   + struct.pack("<H", 6363) + s(b"/ln/lab/arm.state")
                   + struct.pack("<I", 64) + struct.pack("<I", 1000) + b"\x00" + s(b""))
    keyed = dp.encode_pull_topic("t", "r", "m", 0, 8, "::1", 1, "/n", 1, 0, b"\x00\xff")
    assert keyed.endswith(b"\x04" + s(b"\x00\xff"))
    with pytest.raises(struct.error):
        dp.encode_pull_topic("t", "r", "m", 0, 8, "", 65536, "/n", 1, 0)


def test_pull_list_round_trip_and_bytes() -> None:
    status = dp.PullStatus(
        [dp.PullPortStatus("0.0.0.0", 6363, 10, 1, 2, 3, "x")],
        [dp.PullTopicStatus("arm.state", "/ln/a/arm.state", "ring", "0.0.0.0", 6363, 64,
                            500, 11, 12, 13, 14, 15, 16, 17, 18, "")])
    wire = dp.encode_pull_list(status)
    assert wire[:4] == struct.pack("<I", 1)
    assert wire[4:4 + 4 + 7] == s(b"0.0.0.0")
    assert dp.decode_pull_list(wire) == status
    assert dp.decode_pull_list(struct.pack("<II", 0, 0)) == dp.PullStatus([], [])
    with pytest.raises(ValueError, match="short payload"):
        dp.decode_pull_list(wire[:-1])
    with pytest.raises(ValueError, match="bytes left over"):
        dp.decode_pull_list(wire + b"\0")
    with pytest.raises(ValueError, match="short payload"):
        dp.decode_pull_list(struct.pack("<I", 5))
