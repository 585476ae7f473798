"""The one Python home of `HOST:PORT` addresses: parsing `HOST:PORT`, `[V6HOST]:PORT` and,
where a default host applies, `:PORT`; writing them back; and which hosts are this host's
loopback.  libln parses LN_MANAGER by the same rules (client.c)."""

from __future__ import annotations

import ipaddress

Address = tuple[str, int]
LOOPBACK_NAMES = frozenset({"localhost", "localhost.localdomain", "ip6-localhost"})


class AddressError(ValueError):
    """Not an address; the text says which address and what is wrong with it.  `kind`:
    "form" (no HOST:PORT at all), "port", "brackets", "ipv6" (unbracketed) or "blanks"."""

    def __init__(self, message: str, kind: str) -> None:
        super().__init__(message)
        self.kind = kind


def parse_address(text: str, *, default_host: str | None = None,
                  allow_port_zero: bool = False, what: str = "address") -> Address:
    """(host, port) of `HOST:PORT` or `[V6HOST]:PORT` (the host without its brackets); also
    `:PORT` where a `default_host` is given, which it then names.  Port 0 (the kernel picks
    one) only with `allow_port_zero`.  AddressError `bad <what> '<text>': <why>` otherwise;
    where `:PORT` is allowed, a missing HOST:PORT and a bad port get one text naming every
    form (as libln's for LN_MANAGER)."""
    host, colon, port = text.rpartition(":")
    bracketed = host.startswith("[") and host.endswith("]") and len(host) >= 2
    if bracketed:
        host = host[1:-1]
    low = 0 if allow_port_zero else 1

    def bad(why: str, kind: str) -> AddressError:
        if default_host is not None and kind in ("form", "port"):
            why = f"expected HOST:PORT, :PORT or [V6HOST]:PORT with a port {low}..65535"
        return AddressError(f"bad {what} {text!r}: {why}", kind)

    if bracketed and (not host or ":" not in host):
        raise bad("brackets are for IPv6 addresses", "brackets")
    if not bracketed and ":" in host:
        raise bad("an IPv6 address needs brackets, e.g. [::1]:5000", "ipv6")
    if not colon or (not host and (bracketed or default_host is None)):
        raise bad("expected HOST:PORT or [V6HOST]:PORT", "form")
    if any(c.isspace() for c in host):
        raise bad("blanks in the host name", "blanks")
    if not port.isascii() or not port.isdigit() or not low <= int(port) <= 65535:
        raise bad(f"the port must be a number {low}..65535", "port")
    return host or str(default_host), int(port)


def parse_manager_address(text: str) -> Address:
    """A manager's address as LN_MANAGER and --manager give it: `:PORT` means localhost."""
    return parse_address(text, default_host="localhost", what="manager address")


def format_address(address: Address) -> str:
    """`host:port`, with brackets around an IPv6 host."""
    host, port = address
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


def host_of(text: str) -> str:
    """The host of an address as written (without brackets; "" for `:PORT`), or of a bare
    host name; no checks."""
    if text.startswith("["):
        return text[1:].partition("]")[0]
    return text.rpartition(":")[0] if text.count(":") == 1 else text


def is_loopback(host: str) -> bool:
    """True for this host's loopback: 127.0.0.0/8, ::1 (brackets or not) and the usual names
    of localhost."""
    host = host.strip("[]")
    if host in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False
