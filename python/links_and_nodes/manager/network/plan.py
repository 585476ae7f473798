"""Which streams must exist: one per (topic, hop) from the host of a topic's publishers to
each host with subscribers, through gateway hosts where the `network` sections say so, over
the transport the subscriptions or the configuration ask for."""

from __future__ import annotations

from ... import transports
from ..config import model
from ..registry.core import Core
from ..registry.model import PortKind, Topic
from . import routes
from .client_hosts import ClientHosts

SUBSCRIBE_UDP = 0x100  # LN_SUBSCRIBE_UDP
SUBSCRIBE_TCP = 0x200  # LN_SUBSCRIBE_TCP

# (topic id, src host, dst host) of one hop
StreamKey = tuple[int, str, str]


class StreamPlan:
    def __init__(self, config: model.Config, core: Core, clients: ClientHosts) -> None:
        self.config = config
        self.core = core
        self.clients = clients
        self.problems: dict[StreamKey, str] = {}  # no route etc.
        # topic id -> the host of its publishers, also after they left: its ring there
        # holds the topic's sequence number (see Forwarding.transit_needed)
        self.origins: dict[int, str] = {}

    def publisher_host(self, topic: Topic) -> str | None:
        hosts = {self.clients.client_host(p.client) for p in topic.ports.values()
                 if p.kind is PortKind.PUBLISHER}
        return next(iter(hosts)) if len(hosts) == 1 else None

    def transport(self, topic: Topic, host: str) -> str:
        """TCP if a subscription on `host` asks for it, else UDP if one asks for that, else
        the configuration's setting for the topic, else UDP."""
        flags = 0
        for port in topic.ports.values():
            if port.kind is PortKind.SUBSCRIBER and self.clients.client_host(port.client) == host:
                flags |= port.flags
        return (transports.asked(flags, udp_flag=SUBSCRIBE_UDP, tcp_flag=SUBSCRIBE_TCP)
                or model.topic_transport(self.config, topic.name) or transports.DEFAULT_FORWARD)

    def desired(self) -> dict[StreamKey, tuple[str, str, bool]]:
        """(topic id, src, dst) -> (transport, address, final) of every needed hop."""
        want: dict[StreamKey, tuple[str, str, bool]] = {}
        self.problems = {}
        topics = self.core.registry.topics.values()
        self.origins = {t.id: self.origins[t.id] for t in topics if t.id in self.origins}
        for topic in topics:
            src = self.publisher_host(topic)
            if src is None:
                continue
            self.origins[topic.id] = src
            sinks = {self.clients.client_host(p.client) for p in topic.ports.values()
                     if p.kind is PortKind.SUBSCRIBER} - {src, None}
            for dst in sorted(h for h in sinks if h is not None):
                transport = self.transport(topic, dst)
                try:
                    hops = routes.route(self.config, src, dst)
                except routes.NoRoute as exc:
                    self.problems[(topic.id, src, dst)] = str(exc)
                    continue
                for hop in hops:
                    key = (topic.id, hop.src, hop.dst)
                    final = hop.dst == dst or want.get(key, ("", "", False))[2]
                    old = want.get(key)
                    if old is not None and old[0] == transports.TCP:
                        transport = transports.TCP
                    want[key] = (transport, hop.address, final)
        return want
