"""`ln_services`: the services a running ln_manager knows, as a table or as JSON
(docs/manager.md, "ln_services").  Speaks to the manager with protocol.py's codec, as
client `ln_services`: HELLO (with the client key when asked), then LIST_SERVICES.  Needs no libln."""

from __future__ import annotations

import argparse
import json
import os
import socket
import sys
from typing import Any

from ...addresses import format_address, parse_manager_address
from ...tools import client_key
from ...tools import protocol as p
from ...tools.framing import receive

CLIENT_NAME = "ln_services"
TIMEOUT = 10.0  # seconds for connecting and for each answer, as libln's default
COLUMNS = ("name", "provider", "md", "group", "calls", "errors", "address")


class ListingError(Exception):
    """The list could not be fetched; the text says why, in one line."""


def _error_name(code: int) -> str:
    """LN_ENOTFOUND for -2 if libln can be loaded for its error table, else the number."""
    try:
        from ... import _libln

        return f"LN_{_libln.ERRORS_BY_CODE[code].name}"
    except Exception:  # no libln, or a code it does not know
        return f"error {code}"


def _expect(reply: p.Message, request: str, expected: type[p.Message]) -> Any:
    if isinstance(reply, p.Error):
        raise ListingError(f"the manager refused {request}: "
                           f"{_error_name(reply.code)}: {reply.text}")
    if not isinstance(reply, expected):
        raise ListingError(f"the manager answered {request} with "
                           f"{reply.TYPE.name}, expected {expected.TYPE.name}")
    return reply


def _answer(sock: socket.socket, request: p.Message, expected: type[p.Message]) -> Any:
    sock.sendall(p.encode(request))
    return _expect(receive(sock, ListingError), request.TYPE.name, expected)


def fetch(host: str, port: int, timeout: float = TIMEOUT) -> p.ServiceList:
    """The SERVICE_LIST of the manager at host:port; ListingError if there is none."""
    where = format_address((host, port))
    try:
        with socket.create_connection((host, port), timeout=timeout) as sock:
            _expect(client_key.greet(sock, CLIENT_NAME, ListingError), "HELLO", p.Welcome)
            listing: p.ServiceList = _answer(sock, p.ListServices(1), p.ServiceList)
    except TimeoutError:
        raise ListingError(f"no answer from the manager at {where} within {timeout:g} s") \
            from None
    except OSError as exc:
        raise ListingError(f"cannot reach the manager at {where}: "
                           f"{exc.strerror or exc}") from None
    if listing.request_id != 1:
        raise ListingError(f"the manager answered request {listing.request_id}, expected 1")
    return listing


def as_dict(entry: p.ServiceEntry) -> dict[str, Any]:
    """One service for --json; the layout hash as the 0x%016x text logs and errors use."""
    return {"name": entry.name, "md_name": entry.md_name,
            "layout_hash": f"0x{entry.layout_hash:016x}", "provider": entry.provider,
            "group": entry.group, "host_id": entry.host_id, "unix_path": entry.unix_path,
            "tcp_host": entry.tcp_host, "tcp_port": entry.tcp_port, "calls": entry.calls,
            "errors": entry.errors}


def address(entry: p.ServiceEntry) -> str:
    """`unix:PATH` and/or `tcp:HOST:PORT`, as offered."""
    parts = []
    if entry.unix_path:
        parts.append(f"unix:{entry.unix_path}")
    if entry.tcp_port:
        parts.append(f"tcp:{format_address((entry.tcp_host, entry.tcp_port))}")
    return " ".join(parts)


def _cell(text: str) -> str:
    """Printable, one line, never empty: what the provider sent may be anything."""
    text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
    return text or "-"


def table(entries: tuple[p.ServiceEntry, ...]) -> list[str]:
    rows = [list(COLUMNS)] + [
        [_cell(e.name), _cell(e.provider), _cell(e.md_name), _cell(e.group), str(e.calls),
         str(e.errors), _cell(address(e))] for e in entries]
    widths = [max(len(row[i]) for row in rows) for i in range(len(COLUMNS))]
    return ["  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=True))
            .rstrip() for row in rows]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ln_services",
        description="List the services a running links_and_nodes manager knows: name, "
                    "provider, md, group, call counts and addresses.")
    parser.add_argument("--manager", metavar="HOST:PORT",
                        help="the manager's address (default: $LN_MANAGER)")
    parser.add_argument("--json", action="store_true",
                        help="print a JSON list, one object per service")
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    text = args.manager or os.environ.get("LN_MANAGER", "")
    if not text:
        parser.error("no manager address: give --manager HOST:PORT or set LN_MANAGER")
    try:
        host, port = parse_manager_address(text)
    except ValueError as exc:
        parser.error(str(exc))
    try:
        listing = fetch(host, port)
    except ListingError as exc:
        print(f"ln_services: error: {exc}", file=sys.stderr)
        return 1
    if args.json:
        print(json.dumps([as_dict(e) for e in listing.entries], indent=2))
    elif listing.entries:
        print("\n".join(table(listing.entries)))
    elif not listing.total:
        print("no services")
    if len(listing.entries) < listing.total:
        print(f"ln_services: showing {len(listing.entries)} of {listing.total} services: the "
              "list did not fit one frame", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
