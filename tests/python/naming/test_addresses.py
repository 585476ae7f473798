"""links_and_nodes.addresses: HOST:PORT, [V6HOST]:PORT and :PORT, with the error texts."""

from __future__ import annotations

import pytest

from links_and_nodes.addresses import (
    AddressError,
    format_address,
    host_of,
    is_loopback,
    parse_address,
    parse_manager_address,
)


@pytest.mark.parametrize("text, address", [
    ("h:1", ("h", 1)), ("10.0.0.1:65535", ("10.0.0.1", 65535)), ("[::1]:80", ("::1", 80)),
    ("[fe80::1%eth0]:5", ("fe80::1%eth0", 5)), ("robot-pc.lab:6000", ("robot-pc.lab", 6000)),
])
def test_good(text: str, address: tuple[str, int]) -> None:
    assert parse_address(text) == address
    assert parse_address(format_address(address)) == address


@pytest.mark.parametrize("text, why", [
    ("127.0.0.1", "expected HOST:PORT or [V6HOST]:PORT"),
    (":5000", "expected HOST:PORT or [V6HOST]:PORT"),
    ("::1:5000", "an IPv6 address needs brackets, e.g. [::1]:5000"),
    ("[1.2.3.4]:5", "brackets are for IPv6 addresses"),
    ("[]:5", "brackets are for IPv6 addresses"),
    ("host:0", "the port must be a number 1..65535"),
    ("host:65536", "the port must be a number 1..65535"),
    ("host:x", "the port must be a number 1..65535"),
    ("host:\u0661", "the port must be a number 1..65535"),
    ("my host:5", "blanks in the host name"),
])
def test_bad(text: str, why: str) -> None:
    with pytest.raises(AddressError) as info:
        parse_address(text)
    assert str(info.value) == f"bad address {text!r}: {why}"


def test_port_zero_and_default_host() -> None:
    assert parse_address("h:0", allow_port_zero=True) == ("h", 0)
    assert parse_manager_address(":54414") == ("localhost", 54414)
    assert parse_address(":7", default_host="") == ("", 7)
    for bad in ("x", "h:70000"):
        with pytest.raises(AddressError) as info:
            parse_manager_address(bad)
        assert str(info.value) == (f"bad manager address {bad!r}: expected HOST:PORT, :PORT "
                                   "or [V6HOST]:PORT with a port 1..65535")
    with pytest.raises(AddressError, match="an IPv6 address needs brackets"):
        parse_manager_address("::1:5")


def test_hosts() -> None:
    assert [host_of(t) for t in ("h:1", "[::1]:2", "::1", "h", ":3")] == ["h", "::1", "::1",
                                                                          "h", ""]
    assert all(is_loopback(h) for h in ("127.0.0.1", "127.3.4.5", "::1", "[::1]", "localhost"))
    assert not any(is_loopback(h) for h in ("10.0.0.1", "0.0.0.0", "robot", "::"))


def test_the_configuration_takes_the_same_forms() -> None:
    from links_and_nodes.manager.config import ConfigError, parse_text

    for manager in ("[::1]:5000", ":5000", "robot-pc:5000"):
        config = parse_text(f"instance\nname: t\nmanager: {manager}\n", "main.lnc")
        assert config.instance.manager == manager
    with pytest.raises(ConfigError, match="an IPv6 address needs brackets"):
        parse_text("instance\nname: t\nmanager: ::1:5000\n", "main.lnc")
