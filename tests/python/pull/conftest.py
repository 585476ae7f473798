"""Fixtures of the pull-topic end-to-end tests: a real `ln_manager -c` whose configuration
serves topics with `pull:ndn-udp` on a free UDP port (the loggers' LogLab: its own instance,
ports, ln_daemon and key file), C publishers from tests/c/tools, and the manager's views;
and the network tests' `system` of hosts in their own network namespaces."""

from __future__ import annotations

import contextlib
import socket
from collections.abc import Iterator
from typing import Any

import pytest
from loggers import conftest as lc
from loggers.conftest import LogLab
from network import conftest as nc
from polling import wait_for

lab = lc.lab  # the same world as the loggers' tests
system = nc.system  # hosts in network namespaces, as in the network tests


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def udp_port_free(port: int) -> bool:
    """Nothing is bound to 127.0.0.1:port (or the wildcard address) any more."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        try:
            s.bind(("127.0.0.1", port))
        except OSError:
            return False
        return True


class PullLab(LogLab):
    """A LogLab whose configuration serves `pattern` on `port`."""

    def __init__(self, world: Any) -> None:
        super().__init__(world)
        self.port = free_udp_port()
        self.prefix = f"/ln/{world.instance}"

    def serve(self, pattern: str = "arm.*", extra: str = "", body: str = "") -> None:
        self.start(f"topics\n{pattern}: pull:ndn-udp, pull_port:{self.port}, "
                   f"pull_address:127.0.0.1{extra}\n{body}")

    def uri(self, topic: str) -> str:
        return f"{self.prefix}/{topic}"

    def network(self) -> dict[str, Any]:
        with self.lab.connect() as mgr:
            return mgr.command("network")

    def pull_topics(self) -> list[dict[str, Any]]:
        with self.lab.connect() as mgr:
            return mgr.command("pull")["topics"]

    def served(self, topic: str) -> dict[str, Any]:
        """Wait until the daemon serves `topic` without a refusal and holds a sample of it
        (before that, a sync is answered with a NACK); its network entry."""
        def entry() -> dict[str, Any] | None:
            for host in self.network()["pull"]:
                for t in host["topics"]:
                    if t["topic"] == topic and not t["error"] and t["latest_seq"] > 0:
                        return t
            return None
        return wait_for(entry, f"pull topic {topic} served with a sample")  # type: ignore[return-value]

    def counters(self) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
        """(the port's counters, topic -> counters) of the only host."""
        (host,) = self.network()["pull"]
        (port,) = host["ports"]
        return port, {t["topic"]: t for t in host["topics"]}

    def send(self, packets: list[bytes]) -> None:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            for p in packets:
                s.sendto(p, ("127.0.0.1", self.port))

    def ask(self, packet: bytes, timeout: float = 5.0) -> bytes | None:
        """Send one packet from a fresh socket and return the first reply (None: none)."""
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            s.settimeout(timeout)
            s.sendto(packet, ("127.0.0.1", self.port))
            with contextlib.suppress(TimeoutError):
                return s.recv(65535)
        return None


@pytest.fixture
def pulllab(lab: Any) -> Iterator[PullLab]:  # noqa: F811 - the fixture above
    pl = PullLab(lab)
    try:
        yield pl
    finally:
        for clnt in pl.clients:
            clnt.close()
        for proc in pl.procs:
            if proc.poll() is None:
                proc.kill()
            proc.communicate()
