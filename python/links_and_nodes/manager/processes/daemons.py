"""The manager's connections to the ln_daemons of its hosts: which daemon a process's
`node:` means, starting the local daemon when none runs, authenticating with the shared key
and reconnecting after a daemon restart.  Gives the scheduler its Backend."""

from __future__ import annotations

import asyncio
import logging
import socket
from pathlib import Path

from ..config import model
from ..network import routes
from . import daemon_client as dc
from . import daemon_keys as dk
from . import daemon_launch as dl
from . import daemon_wire as dw
from .backend import Backend

log = logging.getLogger("ln_manager")


def arbiter_port() -> int:
    """$LN_ARBITER_PORT, else the default daemon port (DaemonError if the variable is bad)."""
    return dk.default_port()


class DaemonPool:
    def __init__(self, config: model.Config, instance: str, *, key_file: Path | None = None,
                 log_dir: Path | None = None, start_local: bool = True,
                 local_host: str | None = None) -> None:
        self.config = config
        self.local_host = local_host or socket.gethostname()  # the manager's host
        self.instance = instance
        self.key_file = key_file or dk.default_key_file()
        self.log_dir = log_dir
        self.start_local = start_local
        self._clients: dict[tuple[str, int], dc.DaemonClient] = {}
        self._lock = asyncio.Lock()
        self._key: bytes | None = None

    def is_local(self, node: str) -> bool:
        return routes.host_of(self.config, node, self.local_host) == self.local_host

    def address(self, node: str) -> tuple[str, int]:
        """Where the daemon of `node` listens: 127.0.0.1 on the manager's host; else the
        address of the node's host (node_map) in a network it shares with the manager's
        host, or, without such a network, its first interface address (or its name); and
        its daemon_port (or LN_ARBITER_PORT / 54376)."""
        host_name = routes.host_of(self.config, node, self.local_host)
        written = self.config.node_map.get(node, node)  # a `localhost` entry in hosts counts
        host = self.config.hosts.get(written) or self.config.hosts.get(host_name)
        port = (host.daemon_port if host and host.daemon_port else None) or arbiter_port()
        if host_name == self.local_host:
            return routes.LOOPBACK, port
        address = routes.host_address(self.config, self.local_host, host_name)
        return address or routes.default_address(self.config, host_name), port

    def _read_key(self, create: bool) -> bytes:
        if self._key is None:
            if create and not self.key_file.exists():
                log.info("creating daemon key file %s", self.key_file)
                self._key = dk.create_key_file(self.key_file)
            else:
                self._key = dk.read_key_file(self.key_file)
        return self._key

    async def link(self, node: str) -> dc.DaemonClient:
        host, port = self.address(node)
        async with self._lock:
            client = self._clients.get((host, port))
            if client is not None and not client.closed:
                return client
            local = self.is_local(node)
            key = self._read_key(create=local and self.start_local)
            if local and self.start_local:
                log_file = (self.log_dir / f"ln_daemon-{port}.log") if self.log_dir else None
                await dl.ensure_local_daemon(port, self.key_file, log_file)
            try:
                try:
                    client = await dc.DaemonClient.connect(host, port, key, self.instance)
                except dw.DaemonAuthError:
                    # The key files may have been replaced (docs/security.md, "Rotating the
                    # daemon key"): read ours again once before giving up.
                    self._key = None
                    fresh = self._read_key(create=False)
                    if fresh == key:
                        raise
                    client = await dc.DaemonClient.connect(host, port, fresh, self.instance)
            except OSError as exc:
                raise dw.DaemonError(f"cannot reach ln_daemon of node {node!r} at "
                                     f"{host}:{port}: {exc.strerror or exc}") from None
            log.info("connected to ln_daemon of node %r at %s:%d", node, host, port)
            self._clients[(host, port)] = client
            return client

    def local_address(self, node: str) -> str | None:
        """The manager host's address on its connection to the daemon of `node`, which that
        node's host reaches it at; None while there is no such connection."""
        client = self._clients.get(self.address(node))
        if client is None or client.closed:
            return None
        return client.local_address or None

    async def close(self) -> None:
        for client in self._clients.values():
            await client.close()
        self._clients.clear()

    def backend(self) -> Backend:
        return Backend(link=self.link, error_type=dw.DaemonError)
