"""Which host each client runs on, by the host id it gave in its HELLO: the rings its
ports use there, how logs name its host, and the address a service provider is reached at
from a caller on another host."""

from __future__ import annotations

import socket

from ...addresses import is_loopback
from ..config import model
from ..processes.daemons import DaemonPool
from ..registry.core import Core
from ..registry.model import Client, RequestError
from ..registry.rings import Rings
from . import routes
from .monitor import HostState


class ClientHosts:
    def __init__(self, hosts: dict[str, HostState], config: model.Config, core: Core,
                 pool: DaemonPool, local_id: str) -> None:
        self.hosts = hosts
        self.config = config
        self.core = core
        self.pool = pool
        self.local_id = local_id

    def host_of(self, client: Client) -> HostState | None:
        """The client's host; None for the manager's own; RequestError if unknown."""
        if not client.host_id or client.host_id == self.local_id:
            return None
        for host in self.hosts.values():
            if host.host_id == client.host_id:
                return None if host.local else host
        known = ", ".join(f"{h.name}={h.host_id or '?'}" for h in self.hosts.values())
        raise RequestError("ENOTFOUND", f"client {client.name!r} runs on host id "
                           f"{client.host_id!r}, which is none of this manager's hosts "
                           f"({known}); name its host in the configuration and run an "
                           f"ln_daemon there")

    def client_host(self, client: Client) -> str | None:
        """The name of the client's host; None if it is none of the configuration's."""
        try:
            host = self.host_of(client)
        except RequestError:
            return None
        return host.name if host is not None else self.local_name()

    def rings_for(self, client: Client) -> Rings:
        host = self.host_of(client)
        if host is None:
            return self.core.local
        assert host.rings is not None
        return host.rings

    def all_rings(self) -> list[Rings]:
        return [self.core.local] + [h.rings for h in self.hosts.values()
                                    if h.rings is not None and not h.local]

    def rings_of(self, name: str) -> Rings | None:
        """The rings of the host named so; None for a host that is not configured."""
        host = self.hosts.get(name)
        if host is None or host.local:
            return self.core.local if name == self.local_name() else None
        return host.rings

    def host_label(self, client: Client) -> str:
        try:
            host = self.host_of(client)
        except RequestError:
            return client.host_id
        return host.name if host is not None else self.local_name()

    def local_name(self) -> str:
        for host in self.hosts.values():
            if host.local:
                return host.name
        for host in self.hosts.values():
            if self.pool.is_local(host.node):
                return host.name
        for host in self.hosts.values():  # before its daemon answered: by its addresses
            configured = self.config.hosts.get(host.name)
            if configured and any(_own_address(a) for a in configured.interfaces.values()):
                return host.name
        return "localhost"

    def service_host(self, caller: Client, provider: Client, tcp_host: str) -> str:
        if not is_loopback(tcp_host) and tcp_host.strip("[]") not in ("0.0.0.0", "::"):
            return tcp_host
        src, dst = self.client_host(caller), self.client_host(provider)
        if src is None or dst is None or src == dst:
            return tcp_host
        target = routes.host_address(self.config, src, dst)
        if (target is None or target in routes.LOCAL_NAMES) and dst == self.local_name() \
                and src in self.hosts:
            # the manager's host, which the configuration gives no address: the one its
            # connection to the caller's daemon comes from
            target = self.pool.local_address(self.hosts[src].node)
        return target or tcp_host


def _own_address(address: str) -> bool:
    """True if `address` is one of this machine's (this network namespace's) addresses."""
    family = socket.AF_INET6 if ":" in address else socket.AF_INET
    try:
        with socket.socket(family, socket.SOCK_DGRAM) as sock:
            sock.bind((address, 0))
    except OSError:
        return False
    return True
