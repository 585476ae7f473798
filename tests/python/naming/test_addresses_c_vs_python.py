"""libln (client.c, parsing LN_MANAGER) and links_and_nodes.addresses.parse_manager_address
accept the same manager addresses and say the same about the bad ones."""

from __future__ import annotations

import pytest

import links_and_nodes as ln
from links_and_nodes.addresses import AddressError, parse_manager_address

BAD = ["x", "h:", "h:0", "h:65536", "h:12a", "h:+80", "h: 80", "::1:5", "[::1]", "[1.2.3.4]:5",
       "[]:5", "my host:5", ":"]


@pytest.mark.parametrize("text", BAD)
def test_both_refuse_with_the_same_reason(text: str) -> None:
    with pytest.raises(AddressError) as py:
        parse_manager_address(text)
    with pytest.raises(ln.LnError) as c:
        ln.client("naming-test", text)
    why = str(py.value).removeprefix(f"bad manager address {text!r}: ")
    assert f'bad manager address "{text}": {why}' in str(c.value)


@pytest.mark.parametrize("text", ["127.0.0.1:1", ":1", "[::1]:1"])
def test_both_accept(text: str) -> None:
    host, port = parse_manager_address(text)
    assert port == 1 and host in ("127.0.0.1", "localhost", "::1")
    with pytest.raises(ln.LnError) as c:  # nothing listens on port 1
        ln.client("naming-test", text)
    assert "bad manager address" not in str(c.value)
