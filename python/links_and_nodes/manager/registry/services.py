"""The manager's service registry (docs/protocol.md, "Services"): which client provides
which service, under which md and signature, at which addresses, and the call counts its
provider reports.  Pure logic without I/O, like registry.py, whose clients it refers to;
errors are registry.RequestError with LN_E* table names."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from .defaults import SERVICE_LIMIT as DEFAULT_LIMIT  # services per manager
from .model import MAX_NAME, Client, RequestError, md_name_problem, topic_name_problem

MAX_SIGNATURE = 1024  # bytes
MAX_HOST_ID = MAX_NAME  # bytes
MAX_UNIX_PATH = 107  # bytes: sun_path holds 108 including the terminating NUL


@dataclass(frozen=True)
class ServiceOffer:
    """The fields of a REGISTER_SERVICE."""

    name: str
    md_name: str
    layout_hash: int
    signature: str
    group: str
    host_id: str
    unix_path: str
    tcp_host: str
    tcp_port: int


@dataclass(eq=False)
class Service:
    offer: ServiceOffer
    provider: Client
    calls: int = 0
    errors: int = 0

    @property
    def name(self) -> str:
        return self.offer.name

    def as_dict(self) -> dict[str, Any]:
        """Plain data for listings: every field of the offer, provider name and counts."""
        o = self.offer
        return {"name": o.name, "md_name": o.md_name, "layout_hash": o.layout_hash,
                "signature": o.signature, "group": o.group, "provider": self.provider.name,
                "provider_id": self.provider.id, "host_id": o.host_id, "unix_path": o.unix_path,
                "tcp_host": o.tcp_host, "tcp_port": o.tcp_port, "calls": self.calls,
                "errors": self.errors}


def offer_problem(offer: ServiceOffer) -> RequestError | None:
    """The first failing field check of a REGISTER_SERVICE (in the documented order)."""
    problem = (topic_name_problem(offer.name, "service")
               or md_name_problem(offer.md_name))
    if problem:
        return RequestError("EINVAL", problem)
    size = len(offer.signature.encode("utf-8"))
    if not 1 <= size <= MAX_SIGNATURE:
        return RequestError("EMD", f"service {offer.name!r}: signature of {size} bytes, "
                                   f"must be 1..{MAX_SIGNATURE}")
    if offer.signature.count("|") != 1:
        return RequestError("EMD", f"service {offer.name!r}: signature {offer.signature!r} "
                                   "must contain exactly one '|' (request|response)")
    size = len(offer.host_id.encode("utf-8"))
    if size > MAX_HOST_ID:
        return RequestError("EINVAL", f"service {offer.name!r}: host id of {size} bytes, at "
                                      f"most {MAX_HOST_ID}")
    if offer.unix_path:
        size = len(offer.unix_path.encode("utf-8"))
        if not offer.unix_path.startswith("/") or "\0" in offer.unix_path:
            return RequestError("EINVAL", f"service {offer.name!r}: unix path "
                                          f"{offer.unix_path!r} is not an absolute path")
        if size > MAX_UNIX_PATH:
            return RequestError("EINVAL", f"service {offer.name!r}: unix path of {size} "
                                          f"bytes, at most {MAX_UNIX_PATH}")
    elif offer.tcp_port == 0:
        return RequestError("EINVAL", f"service {offer.name!r}: neither a unix path nor a "
                                      "tcp port given")
    return None


def layout_mismatch(name: str, md_name: str, layout_hash: int, service: Service) -> str:
    """The LN_ELAYOUT text of FIND_SERVICE: both md names and hashes."""
    return (f"service '{name}': layout of md '{md_name}' (hash 0x{layout_hash:016x}) "
            f"differs from the service's md '{service.offer.md_name}' "
            f"(hash 0x{service.offer.layout_hash:016x})")


class Services:
    """Services of one manager instance, by name."""

    def __init__(self, limit: int = DEFAULT_LIMIT) -> None:
        if limit < 1:
            raise ValueError(f"service limit must be at least 1, not {limit}")
        self.limit = limit
        self.by_name: dict[str, Service] = {}
        # the clients that looked a service up (FIND_SERVICE), by service name and client
        # id: the callers the graph shows (docs/introspection.md, "graph")
        self.callers: dict[str, dict[int, Client]] = {}

    def register(self, client: Client, offer: ServiceOffer) -> tuple[Service, Service | None]:
        """Register (or, for the same provider, replace) a service; (new, replaced)."""
        problem = offer_problem(offer)
        if problem:
            raise problem
        old = self.by_name.get(offer.name)
        if old is not None and old.provider is not client:
            raise RequestError("EEXIST", f"service {offer.name!r} is already provided by "
                                         f"client {old.provider.name!r} "
                                         f"({old.provider.address})")
        if old is None and len(self.by_name) >= self.limit:
            raise RequestError("ELIMIT", f"service {offer.name!r}: the manager already has "
                                         f"{len(self.by_name)} services, its limit is "
                                         f"{self.limit}")
        service = Service(offer, client)
        self.by_name[offer.name] = service
        return service, old

    def provided(self, client: Client, name: str) -> Service:
        """The service `name` if `client` provides it; else ENOTFOUND."""
        service = self.by_name.get(name)
        if service is None or service.provider is not client:
            raise RequestError("ENOTFOUND", f"client {client.name!r} does not provide "
                                            f"service {name!r}")
        return service

    def unregister(self, client: Client, name: str) -> Service:
        service = self.provided(client, name)
        del self.by_name[name]
        return service

    def unix_path_in_use(self, path: str) -> bool:
        """Whether a registered service still offers the unix socket `path`."""
        return any(s.offer.unix_path == path for s in self.by_name.values())

    def find(self, name: str, md_name: str, layout_hash: int) -> Service:
        service = self.by_name.get(name)
        if service is None:
            raise RequestError("ENOTFOUND", f"service {name!r} is not provided")
        if service.offer.layout_hash != layout_hash:
            raise RequestError("ELAYOUT", layout_mismatch(name, md_name, layout_hash, service))
        return service

    def found(self, client: Client, name: str) -> None:
        """Note that `client` looked service `name` up (it is about to call it)."""
        self.callers.setdefault(name, {})[client.id] = client

    def called(self, client: Client, name: str, calls: int, errors: int) -> Service:
        """Store the cumulative counts a provider reports."""
        service = self.provided(client, name)
        service.calls, service.errors = calls, errors
        return service

    def remove_client(self, client: Client) -> list[Service]:
        """Forget every service of `client` (its connection closed); those services."""
        gone = [s for s in self.by_name.values() if s.provider is client]
        for service in gone:
            del self.by_name[service.name]
        for name in [n for n, who in self.callers.items() if who.pop(client.id, None)
                     and not who]:
            del self.callers[name]
        return gone

    def sorted(self) -> list[Service]:
        """Every service, by name."""
        return [self.by_name[name] for name in sorted(self.by_name)]

    def listing(self) -> list[dict[str, Any]]:
        return [service.as_dict() for service in self.sorted()]
