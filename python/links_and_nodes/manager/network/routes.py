"""Which hosts talk directly, at which address, and over which hosts the others are
reached: pure functions of the `hosts` and `network` sections of a configuration, used to
address the daemons and to plan topic forwarding between hosts.

Host names are those of `hosts` and node_map (see host_of() for a process's `node:`).
Without `network` sections every host reaches every other directly.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import pairwise

from ..config import model

LOOPBACK = "127.0.0.1"
LOCAL_NAMES = frozenset({"localhost", "127.0.0.1", "::1"})  # the manager's own host


@dataclass(frozen=True)
class Hop:
    """One step of a route: `src` sends to `dst` at `address`, an interface address of
    `dst` that `src` reaches directly (or dst's host name, when it has no interfaces)."""

    src: str
    dst: str
    address: str


class NoRoute(Exception):
    """No chain of hosts connects two hosts; the text names both and their networks."""


def host_of(config: model.Config, node: str, local_host: str) -> str:
    """The host a process's or state's `node:` means: node_map applied, `localhost` (and
    127.0.0.1, ::1) replaced by `local_host`, the manager's host name."""
    host = config.node_map.get(node, node)
    return local_host if host in LOCAL_NAMES else host


def config_hosts(config: model.Config) -> list[tuple[str, str]]:
    """(host name, a node that maps to it) of every host the configuration names: the
    `hosts` section, node_map targets and the nodes of processes and states."""
    found: dict[str, str] = {}
    for node, host in config.node_map.items():
        found.setdefault(host, node)
    for name in config.hosts:
        found.setdefault(name, name)
    nodes = [p.node for p in config.processes.values()]
    nodes += [s.node for s in config.states.values() if s.node]
    for node in nodes:
        found.setdefault(config.node_map.get(node, node), node)
    return sorted(found.items())


def spans_hosts(config: model.Config, local_host: str) -> bool:
    """Whether the configuration names a host other than the manager's (`local_host`):
    one that runs a process or state, or one where clients started by hand may run."""
    return any(host_of(config, node, local_host) != local_host
               for _, node in config_hosts(config))


def default_address(config: model.Config, host: str) -> str:
    """How `host` is reached without networks: its first interface address in `hosts`,
    else its name (resolved by the system)."""
    entry = config.hosts.get(host)
    if entry is not None and entry.interfaces:
        return next(iter(entry.interfaces.values()))
    return host


def host_address(config: model.Config, src_host: str, dst_host: str) -> str | None:
    """The address of `dst_host` that `src_host` reaches directly, or None if the two share
    no network.  Without networks: dst's default_address(); the same host: 127.0.0.1."""
    if src_host == dst_host:
        return LOOPBACK
    if not config.networks:
        return default_address(config, dst_host)
    return _Topology(config).address(src_host, dst_host)


def route(config: model.Config, src_host: str, dst_host: str) -> list[Hop]:
    """The hops from `src_host` to `dst_host`: [] for the same host, one hop for hosts
    that share a network, else the shortest chain through hosts that forward (fewest hops;
    among those, most gateways that a network involved lists in preferred_gateways; then
    by host names).  Raises NoRoute if there is none."""
    if src_host == dst_host:
        return []
    if not config.networks:
        return [Hop(src_host, dst_host, default_address(config, dst_host))]
    return _Topology(config).route(src_host, dst_host)


class _Topology:
    """The hosts of the networks as a graph: an edge joins two hosts that have an interface
    in a common network."""

    def __init__(self, config: model.Config) -> None:
        self.config = config
        self.networks = list(config.networks.values())
        self.members = {net.name: set(net.hosts()) for net in self.networks}
        self.member_of: dict[str, list[model.Network]] = {}
        for net in self.networks:
            for host in net.hosts():
                self.member_of.setdefault(host, []).append(net)
        self.neighbours = {
            host: sorted({other for net in nets for other in self.members[net.name]} - {host})
            for host, nets in self.member_of.items()}

    def common(self, a: str, b: str) -> model.Network | None:
        """The first network (in file order) with an interface of both hosts."""
        for net in self.member_of.get(a, []):
            if b in self.members[net.name]:
                return net
        return None

    def address(self, src: str, dst: str) -> str | None:
        net = self.common(src, dst)
        if net is None:
            return None
        return next(i.address for i in net.interfaces if i.host == dst)

    def preferred(self, before: str, gateway: str, after: str) -> bool:
        """Whether a network of the hops into or out of `gateway` prefers it."""
        return any(gateway in net.preferred_gateways
                   and (before in self.members[net.name] or after in self.members[net.name])
                   for net in self.member_of[gateway])

    def route(self, src: str, dst: str) -> list[Hop]:
        if src not in self.member_of or dst not in self.member_of:
            raise self.no_route(src, dst)
        # Hops to dst from every host that can reach it (breadth-first from dst).
        dist = {dst: 0}
        frontier = [dst]
        while frontier and src not in dist:
            nxt = []
            for host in frontier:
                for other in self.neighbours[host]:
                    if other not in dist:
                        dist[other] = dist[host] + 1
                        nxt.append(other)
            frontier = nxt
        if src not in dist:
            raise self.no_route(src, dst)
        # Among the shortest paths, the one with fewest gateways that are not preferred,
        # then the smallest sequence of host names.  A gateway's preference depends on the
        # hosts before and after it, so the state is (previous host, host).
        memo: dict[tuple[str | None, str], tuple[int, tuple[str, ...]]] = {}

        def best(before: str | None, host: str) -> tuple[int, tuple[str, ...]]:
            if host == dst:
                return 0, ()
            key = (before, host)
            if key not in memo:
                options = []
                for after in self.neighbours[host]:
                    if dist.get(after) == dist[host] - 1:
                        cost, rest = best(host, after)
                        penalty = int(before is not None
                                      and not self.preferred(before, host, after))
                        options.append((cost + penalty, (after, *rest)))
                memo[key] = min(options)
            return memo[key]

        path = (src, *best(None, src)[1])
        hops = []
        for a, b in pairwise(path):
            address = self.address(a, b)
            assert address is not None
            hops.append(Hop(a, b, address))
        return hops

    def no_route(self, src: str, dst: str) -> NoRoute:
        def where(host: str) -> str:
            if host not in self.config.hosts:
                return f"'{host}' has no entry in 'hosts', so it is in no network"
            nets = [net.name for net in self.member_of.get(host, [])]
            if not nets:
                return f"'{host}' is in no network"
            return f"'{host}' is in network{'s' if len(nets) > 1 else ''} {', '.join(nets)}"

        text = f"no route from host '{src}' to host '{dst}': {where(src)}; {where(dst)}"
        if src in self.member_of and dst in self.member_of:
            text += "; no chain of hosts with common networks connects them"
        return NoRoute(text)
