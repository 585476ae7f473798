"""Whatever one connection sends, only that connection suffers: every malformed frame or
protocol violation closes it with one log line giving the reason, releases what its
client held, and a client connected before keeps working."""

from __future__ import annotations

import socket
import struct

import lnwire
import pytest
from lnwire import frame, s
from mgrproc import Manager, require_manager_library, segments, wait_for

require_manager_library()

import links_and_nodes as ln  # noqa: E402  (after the skip check)

TOPIC_INFO_1 = struct.pack("<I", 1)

# (id, bytes sent after HELLO — or before it when the id says so, reason in the log)
BAD = [
    ("garbage", b"GET / HTTP/1.1\r\nHost: x\r\n\r\n",
     "frame length 542393671 out of range 2..1048576"),
    ("length-2GiB", struct.pack("<I", 2 << 30),
     "frame length 2147483648 out of range 2..1048576"),
    ("length-1", struct.pack("<IB", 1, 0), "frame length 1 out of range 2..1048576"),
    ("length-0", struct.pack("<I", 0), "frame length 0 out of range 2..1048576"),
    ("unknown-type", frame(99, b"abc"), "unknown frame type 99"),
    ("type-0", frame(0, b""), "unknown frame type 0"),
    ("body-too-long", frame(lnwire.TOPIC_INFO, TOPIC_INFO_1 + s("t") + b"\0"),
     "TOPIC_INFO body too long: 8 bytes, its fields take 7"),
    ("body-too-short", frame(lnwire.CLOSE_PORT, TOPIC_INFO_1 + b"\1\0"),
     "CLOSE_PORT body too short: 6 bytes, ends inside port_id"),
    ("str-past-end", frame(lnwire.TOPIC_INFO, TOPIC_INFO_1 + struct.pack("<H", 50) + b"abc"),
     "TOPIC_INFO body too short: 9 bytes, topic needs 50 bytes at offset 6"),
    ("bad-utf8", frame(lnwire.TOPIC_INFO, TOPIC_INFO_1 + s(b"robot.\xc3\x28")),
     r"TOPIC_INFO.topic: not valid UTF-8 \(byte 6\)"),
    ("bad-utf8-publish", frame(lnwire.PUBLISH, lnwire.port_body(1, "t", b"m/\xff", 1, 8)),
     r"PUBLISH.md_name: not valid UTF-8 \(byte 2\)"),
    ("str-over-1024", frame(lnwire.TOPIC_INFO, TOPIC_INFO_1 + s("x" * 1025)),
     "TOPIC_INFO.topic: str of 1025 bytes, at most 1024"),
    ("request-id-0", frame(lnwire.TOPIC_INFO, struct.pack("<I", 0) + s("t")),
     r"TOPIC_INFO with request id 0 \(must be non-zero\)"),
    ("reply-type", frame(lnwire.OK, TOPIC_INFO_1), "unexpected OK frame from a client"),
    ("welcome", frame(lnwire.WELCOME, b""), "unexpected WELCOME frame from a client"),
    ("truncated-body", struct.pack("<IH", 40, lnwire.TOPIC_INFO) + b"12345",
     "truncated frame: connection closed after 7 of 40 bytes"),
    ("truncated-header", b"\x10\x00",
     "truncated frame: connection closed after 2 of 4 header bytes"),
]


@pytest.fixture
def bystander(manager: Manager) -> lnwire.WireClient:
    """A client connected before the bad one, holding a topic."""
    client = manager.client("bystander")
    assert client.publish("calm", "m/d", 1, 8).type == lnwire.PORT_OK
    return client


def still_fine(client: lnwire.WireClient) -> None:
    info = client.topic_info("calm")
    assert (info.type, info.publishers) == (lnwire.TOPIC_INFO_OK, 1)
    assert client.subscribe("calm", "m/d", 1, 8).type == lnwire.PORT_OK


def send_and_wait_closed(manager: Manager, data: bytes, hello: str | None) -> None:
    client = manager.client(hello)
    client.send_raw(data)
    client.sock.shutdown(socket.SHUT_WR)  # a truncated frame stays truncated
    assert client.closed_by_peer()
    client.close()


@pytest.mark.parametrize("data, reason", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_frame_after_hello(manager: Manager, bystander: lnwire.WireClient, data: bytes,
                               reason: str) -> None:
    send_and_wait_closed(manager, data, "evil")
    manager.wait_log(rf"^.* client evil \(127\.0\.0\.1:\d+\): closing: {reason}$")
    still_fine(bystander)


@pytest.mark.parametrize("data, reason", [b[1:] for b in BAD[:6]], ids=[b[0] for b in BAD[:6]])
def test_bad_frame_instead_of_hello(manager: Manager, bystander: lnwire.WireClient,
                                    data: bytes, reason: str) -> None:
    send_and_wait_closed(manager, data, None)
    manager.wait_log(rf"^.* client \? \(127\.0\.0\.1:\d+\): closing: {reason}$")
    still_fine(bystander)


def test_oversized_length_is_refused_before_the_body(manager: Manager,
                                                     bystander: lnwire.WireClient) -> None:
    """The manager must not wait for (or buffer) 2 GiB: it closes right after the header,
    while the sender's side of the connection is still open."""
    client = manager.client("big")
    client.send_raw(struct.pack("<IH", 2 << 30, lnwire.PUBLISH) + b"x" * 1000)
    assert client.closed_by_peer()
    client.close()
    still_fine(bystander)


def test_a_closed_bad_client_loses_its_ports(manager: Manager,
                                             bystander: lnwire.WireClient) -> None:
    evil = manager.client("evil")
    assert evil.publish("evil.topic", "m/d", 1, 8).type == lnwire.PORT_OK
    assert evil.subscribe("calm", "m/d", 1, 8).type == lnwire.PORT_OK
    assert len(segments(manager.instance)) == 2
    evil.send_raw(frame(99, b""))
    assert evil.closed_by_peer()
    manager.wait_log(r"client evil \(.*\): disconnected, released 2 ports")
    assert bystander.topic_info("evil.topic").code == ln.LnNotfoundError.code
    assert bystander.topic_info("calm").subscribers == 0
    assert segments(manager.instance) == [f"ln.{manager.instance}.1.1"]


def test_many_bad_connections_at_once(manager: Manager, bystander: lnwire.WireClient) -> None:
    clients = [manager.client() for _ in range(20)]
    for i, client in enumerate(clients):
        client.send_raw(BAD[i % len(BAD)][1])
        client.sock.shutdown(socket.SHUT_WR)
    for client in clients:
        assert client.closed_by_peer()
        client.close()
    still_fine(bystander)
    wait_for(lambda: manager.log().count(": closing: ") >= 20, "20 closing lines")
