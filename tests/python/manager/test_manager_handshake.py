"""HELLO/WELCOME against a running ln_manager: the names clients get, version and magic
checks, the host id kept with a client, and what happens to a connection that does not
start with a proper HELLO."""

from __future__ import annotations

import struct

import lnwire
import pytest
from mgrproc import Manager, require_manager_library

require_manager_library()

import links_and_nodes as ln  # noqa: E402  (after the skip check)
from links_and_nodes.manager.registry.core import Core, HandshakeRefused, Session  # noqa: E402
from links_and_nodes.manager.registry.model import Registry  # noqa: E402
from links_and_nodes.manager.registry.services import Services  # noqa: E402
from links_and_nodes.tools import protocol as p  # noqa: E402

ADDR = r"\(127\.0\.0\.1:\d+\)"


class _NoSegments:
    """A handshake never touches segments; this stands in for them."""


def test_hello_welcome(manager: Manager) -> None:
    with manager.client() as client:
        welcome = client.hello("controller")
        assert welcome.type == lnwire.WELCOME
        assert welcome.version == 3
        assert welcome.client_id >= 1
        assert welcome.client_name == "controller"
        assert welcome.instance_name == manager.instance
    manager.wait_log(rf"client controller {ADDR}: connected \(pid \d+, library 0\.1\.0, "
                     r"host test-host/1\)")


def test_host_id_is_kept_with_the_client() -> None:
    registry = Registry(lambda size, slots: size * slots)
    core = Core("inst", registry, _NoSegments(), Services())  # type: ignore[arg-type]
    session = Session("127.0.0.1:9")
    core.hello(session, p.Hello(p.MAGIC, p.VERSION, 42, "ctl", "0.1.0", "rack-ä/7"))
    assert session.client is not None and session.client.host_id == "rack-ä/7"
    with pytest.raises(HandshakeRefused) as info:
        core.hello(Session("127.0.0.1:10"), p.Hello(p.MAGIC, p.VERSION, 43, "far", "0.1.0",
                                                    "h" * 256))
    assert info.value.reply == p.Error(0, ln.LnInvalError.code,
                                       "host id of 256 bytes, at most 255")


def test_taken_names_get_suffixes(manager: Manager) -> None:
    first, second, third = (manager.client("ctl") for _ in range(3))
    assert [c.name for c in (first, second, third)] == ["ctl", "ctl-2", "ctl-3"]
    for client in (first, second, third):  # each one is a working connection
        assert client.topic_info("x").code == ln.LnNotfoundError.code
    second.close()
    manager.wait_log(rf"client ctl-2 {ADDR}: disconnected")
    with manager.client("ctl") as again:
        assert again.name == "ctl-2"  # free again
    first.close()
    third.close()


def test_version_mismatch(manager: Manager) -> None:
    with manager.client() as client:
        error = client.hello("future", version=4)
        assert error.type == lnwire.ERROR
        assert error.request_id == 0
        assert error.code == ln.LnVersionError.code
        assert error.text == "client speaks protocol 4, manager speaks 3"
        assert client.closed_by_peer()
    manager.wait_log(rf"client \? {ADDR}: closing: handshake refused: client speaks "
                     "protocol 4, manager speaks 3")


def test_protocol_1_client_is_told_the_versions(manager: Manager) -> None:
    with manager.client() as client:  # a HELLO of protocol 1: no host id
        client.send(lnwire.HELLO, struct.pack("<IHI", lnwire.MAGIC, 1, 77) + lnwire.s("old")
                    + lnwire.s("0.1.0"))
        error = client.recv()
        assert (error.type, error.code) == (lnwire.ERROR, ln.LnVersionError.code)
        assert error.text == "client speaks protocol 1, manager speaks 3"
        assert client.closed_by_peer()


def test_protocol_2_client_is_told_the_versions(manager: Manager) -> None:
    with manager.client() as client:  # a HELLO of protocol 2: no flags
        client.send(lnwire.HELLO, struct.pack("<IHI", lnwire.MAGIC, 2, 77) + lnwire.s("old")
                    + lnwire.s("0.1.0") + lnwire.s("h/1"))
        error = client.recv()
        assert (error.type, error.code) == (lnwire.ERROR, ln.LnVersionError.code)
        assert error.text == "client speaks protocol 2, manager speaks 3"
        assert client.closed_by_peer()


def test_other_version_may_have_another_hello_layout(manager: Manager) -> None:
    with manager.client() as client:
        client.send(lnwire.HELLO, struct.pack("<IH", lnwire.MAGIC, 4) + b"\x01\x02\x03")
        error = client.recv()
        assert (error.type, error.code) == (lnwire.ERROR, ln.LnVersionError.code)
        assert error.text == "client speaks protocol 4, manager speaks 3"
        assert client.closed_by_peer()


def test_wrong_magic_is_malformed(manager: Manager) -> None:
    with manager.client() as client:
        client.send(lnwire.HELLO, lnwire.hello_body("x", magic=0x4C4E4D50))
        assert client.closed_by_peer()
    manager.wait_log(rf"client \? {ADDR}: closing: HELLO with wrong magic 0x4c4e4d50, "
                     "expected 0x504d4e4c")


def test_first_frame_must_be_hello(manager: Manager) -> None:
    with manager.client() as client:
        client.send(lnwire.TOPIC_INFO, struct.pack("<I", 1) + lnwire.s("t"))
        assert client.closed_by_peer()
    manager.wait_log(rf"client \? {ADDR}: closing: first frame is type 15, expected HELLO")


def test_second_hello_is_a_violation(manager: Manager) -> None:
    client = manager.client("twice")
    client.send(lnwire.HELLO, lnwire.hello_body("twice"))
    assert client.closed_by_peer()
    manager.wait_log(rf"client twice {ADDR}: closing: second HELLO on one connection")


def test_unusable_client_names_are_refused(manager: Manager) -> None:
    for name in ("", "line\nbreak"):
        with manager.client() as client:
            error = client.hello(name)
            assert (error.type, error.code) == (lnwire.ERROR, ln.LnInvalError.code)
            assert "client name" in error.text
            assert client.closed_by_peer()


def test_a_connection_that_says_nothing(manager: Manager) -> None:
    manager.client().close()
    with manager.client("after") as client:
        assert client.name == "after"
