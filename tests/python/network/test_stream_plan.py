"""Which streams the manager asks the daemons for (network.Network.desired), without any
daemon: one hop per host pair sharing a network, gateways where they do not, the transport
from the subscriptions, then the .lnc, then UDP; nothing for a topic without remote
subscribers."""

from __future__ import annotations

from typing import Any

from links_and_nodes.manager.config import parse_text
from links_and_nodes.manager.network.hosts import SUBSCRIBE_TCP, SUBSCRIBE_UDP, Network
from links_and_nodes.manager.registry.core import Core
from links_and_nodes.manager.registry.model import PortKind, PortRequest, Registry
from links_and_nodes.manager.registry.services import Services

LNC = """instance
name: plan
manager: :54999

hosts
a: eth0: 10.0.1.1
g: eth0: 10.0.1.2, eth1: 10.0.2.2
b: eth0: 10.0.2.3
c: eth0: 10.0.1.4

network upper
member_interfaces: 10.0.1.0/24

network lower
member_interfaces: g/eth1, b/eth0

topics
log.*: transport: tcp

process p
node: a
command: true
"""


class _Pool:
    def is_local(self, node: str) -> bool:
        return False


class _Segments:
    def has(self, topic_id: int) -> bool:
        return False


def _network(extra: str = "") -> tuple[Network, Registry]:
    config = parse_text(LNC + extra, "plan.lnc")
    registry = Registry(lambda size, slots: size * slots)
    core = Core("plan", registry, _Segments(), Services())  # type: ignore[arg-type]
    net = Network(config, core, _Pool(), "plan")  # type: ignore[arg-type]
    for name, host in net.hosts.items():
        host.host_id, host.state = f"id-{name}", "up"
    return net, registry


def _port(registry: Registry, host: str, kind: PortKind, topic: str, flags: int = 0) -> Any:
    client = registry.add_client(f"{host}-{kind.value}", 1, "x", "0", f"id-{host}")
    plan = registry.plan_port(client, PortRequest(kind, topic, "m/d", 7, 8, 1, flags))
    found = plan.topic or registry.add_topic(plan)
    return registry.add_port(plan, found)


def test_direct_and_through_a_gateway() -> None:
    net, registry = _network()
    _port(registry, "a", PortKind.PUBLISHER, "arm.state")
    _port(registry, "c", PortKind.SUBSCRIBER, "arm.state")
    _port(registry, "b", PortKind.SUBSCRIBER, "arm.state")
    _port(registry, "a", PortKind.SUBSCRIBER, "arm.state")  # local: no stream
    tid = registry.topics["arm.state"].id
    assert net.desired() == {
        (tid, "a", "c"): ("udp", "10.0.1.4", True),
        (tid, "a", "g"): ("udp", "10.0.1.2", False),  # g only passes it on
        (tid, "g", "b"): ("udp", "10.0.2.3", True),
    }


def test_transport_from_subscription_then_lnc_then_udp() -> None:
    net, registry = _network()
    _port(registry, "a", PortKind.PUBLISHER, "arm.state")
    _port(registry, "c", PortKind.SUBSCRIBER, "arm.state", SUBSCRIBE_TCP)
    _port(registry, "a", PortKind.PUBLISHER, "log.events")
    _port(registry, "c", PortKind.SUBSCRIBER, "log.events")  # the .lnc says tcp
    _port(registry, "g", PortKind.SUBSCRIBER, "log.events", SUBSCRIBE_UDP)  # overrides it
    want = net.desired()
    state, log = registry.topics["arm.state"].id, registry.topics["log.events"].id
    assert want[(state, "a", "c")][0] == "tcp"
    assert want[(log, "a", "c")][0] == "tcp"
    assert want[(log, "a", "g")][0] == "udp"


def test_tcp_anywhere_behind_a_gateway_makes_the_shared_hop_tcp() -> None:
    net, registry = _network()
    _port(registry, "a", PortKind.PUBLISHER, "arm.state")
    _port(registry, "b", PortKind.SUBSCRIBER, "arm.state", SUBSCRIBE_TCP)
    _port(registry, "g", PortKind.SUBSCRIBER, "arm.state", SUBSCRIBE_UDP)
    want = net.desired()
    tid = registry.topics["arm.state"].id
    assert want[(tid, "a", "g")] == ("tcp", "10.0.1.2", True)
    assert want[(tid, "g", "b")] == ("tcp", "10.0.2.3", True)


def test_no_streams_without_remote_subscribers_or_publisher() -> None:
    net, registry = _network()
    _port(registry, "a", PortKind.PUBLISHER, "only.local")
    _port(registry, "a", PortKind.SUBSCRIBER, "only.local")
    _port(registry, "b", PortKind.SUBSCRIBER, "no.publisher")
    assert net.desired() == {}


def test_unroutable_pair_is_a_problem_not_a_stream() -> None:
    net, registry = _network("\nhosts\nz: eth0: 172.16.0.9\n")
    _port(registry, "a", PortKind.PUBLISHER, "arm.state")
    _port(registry, "z", PortKind.SUBSCRIBER, "arm.state")
    assert net.desired() == {}
    (problem,) = net.problems.values()
    assert "'a'" in problem and "'z'" in problem


async def test_console_shows_streams_and_pairs() -> None:
    import io

    from links_and_nodes.manager.frontends.console import Console

    class _Control:
        async def handle(self, command: dict[str, Any]) -> dict[str, Any]:
            if command["op"] == "hosts":
                return {"ok": True, "hosts": [
                    {"name": "a", "state": "up", "error": "", "host_id": "id-a",
                     "data_port": 54377, "local": True, "for_s": 3.0},
                    {"name": "b", "state": "unreachable", "error": "no answer from its "
                     "ln_daemon", "host_id": "", "data_port": 0, "local": False,
                     "for_s": 1.0}]}
            return {"ok": True, "streams": [
                {"topic": "arm.state", "src": "a", "dst": "b", "transport": "udp",
                 "msgs_per_s": 1000.0, "bytes_per_s": 180000, "sent": 5000,
                 "received": 4990, "drops": 10, "stale": 2, "error": ""}],
                "pairs": [{"src": "a", "dst": "b", "topics": 1, "msgs_per_s": 1000.0,
                           "bytes_per_s": 180000, "drops": 10}],
                "problems": [{"topic": "x", "src": "a", "dst": "z",
                              "error": "no route"}]}

    out = io.StringIO()
    console = Console(_Control(), out)  # type: ignore[arg-type]
    await console.execute("network")
    await console.execute("hosts")
    text = out.getvalue().splitlines()
    assert any(line.split()[:4] == ["arm.state", "a", "b", "udp"] and "180.0 KB" in line
               and "4990" in line for line in text), text
    assert any(line.split()[:3] == ["a", "b", "1"] for line in text), text
    assert any(line.startswith("x ") and line.endswith("no route") for line in text), text
    assert any(line.startswith("a *") and "54377" in line for line in text), text
    assert any(line.startswith("b ") and "unreachable" in line
               and line.endswith("no answer from its ln_daemon") for line in text), text
