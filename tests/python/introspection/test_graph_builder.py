"""The graph's builder (manager/introspection/graph.py) on a registry made here, without a
running system: two hosts with a stream between them (the subscriber's edge forwarded, with
the stream's rate), a pull topic, a process depending on a state, a bridge found by its
command, a second client of a process merged into its node, and a client nobody started."""

from __future__ import annotations

import asyncio
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any

from links_and_nodes.manager.introspection.graph import Builder, bridge_of, graph
from links_and_nodes.manager.registry.model import PortKind, PortRequest, Registry
from links_and_nodes.manager.registry.services import ServiceOffer, Services

HOSTS = {"cam": "vision_pc", "arm": "robot_pc", "fox": "robot_pc", "arm_tool": "robot_pc",
         "viewer": "vision_pc"}


@dataclass
class Hosts:
    def host_label(self, client: Any) -> str:
        return HOSTS[client.name.split("-")[0]]


@dataclass
class Core:
    registry: Registry
    service_registry: Services
    hosts: Hosts = field(default_factory=Hosts)

    async def topic_published(self, name: str) -> int:
        return {"cam.image": 100, "arm.state": 50}.get(name, 0)


@dataclass(eq=False)
class Control:
    """What the graph uses of the manager's Control (weakly referable, as that is)."""

    core: Core
    scheduler: Any
    network_view: Any
    pull: Any


def proc(name: str, node: str, pid: int | None, command: str, depends: list[str]) -> Any:
    cfg = SimpleNamespace(node=node, command=command, depends_on=depends)
    return SimpleNamespace(cfg=cfg, pid=pid, state=SimpleNamespace(value="ready"))


def system() -> Any:
    reg = Registry(lambda size, slots: size * slots)
    clients = {name: reg.add_client(name, pid, "127.0.0.1:1", "1.0")
               for name, pid in (("cam", 11), ("arm", 12), ("fox", 13), ("arm_tool", 12),
                                 ("viewer", 99))}

    def port(client: str, topic: str, kind: PortKind) -> None:
        plan = reg.plan_port(clients[client], PortRequest(kind, topic, "x/y", 7, 16, 1, 0))
        reg.add_port(plan, plan.topic or reg.add_topic(plan))

    port("cam", "cam.image", PortKind.PUBLISHER)
    port("arm", "cam.image", PortKind.SUBSCRIBER)  # on another host: forwarded
    port("viewer", "cam.image", PortKind.SUBSCRIBER)  # on the same host: shm
    port("arm", "arm.state", PortKind.PUBLISHER)
    port("fox", "arm.state", PortKind.SUBSCRIBER)
    services = Services()
    services.register(clients["arm"], ServiceOffer("arm.move", "x/move", 1, "a|b", "", "",
                                                   "/tmp/s", "", 0))
    services.found(clients["viewer"], "arm.move")
    sched = SimpleNamespace(
        procs={"camera": proc("camera", "vision_pc", 11, "cam_driver", ["power"]),
               "arm": proc("arm", "robot_pc", 12, "arm_ctl", ["camera"]),
               "foxglove": proc("foxglove", "robot_pc", 13, "ln_foxglove --port 0", [])},
        states={"power": SimpleNamespace(up=True)},
        config=SimpleNamespace(groups={"sensors": SimpleNamespace(members=["camera"])}))
    stream = {"topic": "cam.image", "src": "vision_pc", "dst": "robot_pc",
              "transport": "tcp", "msgs_per_s": 29.5, "bytes_per_s": 472, "drops": 3,
              "error": ""}
    network = SimpleNamespace(stream_listing=lambda: {"streams": [stream]})
    pull = SimpleNamespace(listing=lambda: [{"topic": "arm.state", "host": "robot_pc",
                                             "name": "/robot/arm/state", "port": 6363,
                                             "error": ""}])
    return Control(Core(reg, services), sched, network, pull)


def test_nodes_and_edges_of_two_hosts() -> None:
    control = system()
    counted = {"t:cam.image": 100, "t:arm.state": 50, "s:arm.move": 0}
    g = Builder(control, counted, {"t:cam.image": 30.0, "t:arm.state": 10.0}).build(1.0)
    nodes = {n["id"]: n for n in g["nodes"]}
    assert set(nodes) == {"p:camera", "p:arm", "p:foxglove", "c:viewer", "st:power",
                          "t:cam.image", "t:arm.state", "s:arm.move",
                          "u:arm.state@robot_pc"}
    assert nodes["p:arm"]["clients"] == ["arm", "arm_tool"]  # same pid, same host
    assert nodes["p:foxglove"]["bridge"] == "foxglove" and nodes["p:arm"]["bridge"] == ""
    assert nodes["p:camera"]["group"] == "sensors" and nodes["p:camera"]["host"] == "vision_pc"
    assert nodes["c:viewer"]["host"] == "vision_pc" and nodes["c:viewer"]["state"] == \
        "connected"
    assert nodes["t:cam.image"]["bytes_per_s"] == 30 * 16
    edges = {(e["from"], e["to"], e["kind"]): e for e in g["edges"]}
    assert set(edges) == {
        ("p:camera", "t:cam.image", "publishes"), ("t:cam.image", "p:arm", "subscribes"),
        ("t:cam.image", "c:viewer", "subscribes"), ("p:arm", "t:arm.state", "publishes"),
        ("t:arm.state", "p:foxglove", "subscribes"), ("s:arm.move", "p:arm", "provides"),
        ("c:viewer", "s:arm.move", "calls"), ("t:arm.state", "u:arm.state@robot_pc", "pull"),
        ("p:camera", "st:power", "depends_on"), ("p:arm", "p:camera", "depends_on")}
    far = edges[("t:cam.image", "p:arm", "subscribes")]
    assert far["transport"] == "forwarded tcp" and far["rate_hz"] == 29.5
    assert far["forwarded"] == {"src": "vision_pc", "dst": "robot_pc", "transport": "tcp",
                                "drops": 3}
    near = edges[("t:cam.image", "c:viewer", "subscribes")]
    assert near["transport"] == "shm" and near["rate_hz"] == 30.0
    assert g["hosts"] == ["robot_pc", "vision_pc"]
    assert g["groups"] == [{"name": "sensors", "members": ["camera"]}]
    assert [s["drops"] for s in g["streams"]] == [3]


def test_a_caller_that_goes_is_no_caller() -> None:
    control = system()
    services = control.core.service_registry
    viewer = next(c for c in control.core.registry.clients.values() if c.name == "viewer")
    services.remove_client(viewer)
    assert services.callers == {}


def test_the_first_look_waits_for_a_second() -> None:
    control = system()
    first = asyncio.run(graph(control, {"window": 0}))
    assert first["rate_span_s"] is None
    second = asyncio.run(graph(control, {"window": 0.6}))  # no base yet: two looks
    assert second["rate_span_s"] is not None and second["rate_span_s"] >= 0.5


def test_bridges_by_name_or_command() -> None:
    assert bridge_of("python3 -m links_and_nodes.zenoh_bridge.cli") == "zenoh"
    assert bridge_of("ln_record -o x.mcap") == "record"
    assert bridge_of("ln_script") == "tool" and bridge_of("controller") == ""
