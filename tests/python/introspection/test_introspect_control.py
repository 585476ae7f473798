"""The manager's introspection CONTROL commands (introspect_control.py) on a registry built
by the test, with a network view of two hosts: ports, hosts and transports of `topic_info`
(forwarded subscribers too), the md search path of a configuration, `md_show`."""

from __future__ import annotations

import asyncio
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from links_and_nodes.manager.frontends.control import Control
from links_and_nodes.manager.registry.model import Client, PortKind, PortRequest, Registry
from links_and_nodes.tools import protocol as p
from links_and_nodes.tools.commands import ControlError

from .conftest import MDS, OTHER_MDS

HOSTS = {"pub": "robot_pc", "near": "robot_pc", "far": "vision_pc"}


class Rings:
    def __init__(self, host: str, names: list[str]) -> None:
        self.host, self.names = host, names

    def has(self, topic_id: int) -> bool:
        return True

    def current(self, topic_id: int) -> str:
        return self.names[-1]


class Hosts:
    def __init__(self, local: Rings) -> None:
        self.local, self.remote = local, Rings("vision_pc", ["/ln.x.1.1.h2"])

    def all_rings(self) -> list[Rings]:
        return [self.local, self.remote]

    def host_label(self, client: Client) -> str:
        return HOSTS[client.name]

    def local_name(self) -> str:
        return "robot_pc"


def control_with_topic(streams: list[dict[str, Any]], config: Any = None) -> Control:
    registry = Registry(lambda size, slots: size * slots)
    clients = {name: registry.add_client(name, 100 + i, f"127.0.0.1:{4000 + i}", "0.1.0",
                                          f"{HOSTS[name]}/boot")
               for i, name in enumerate(HOSTS)}
    topic = None
    for name, kind, buffers, flags in [("pub", PortKind.PUBLISHER, 1,
                                        p.PUBLISH_WAIT_FOR_SUBSCRIBERS),
                                       ("near", PortKind.SUBSCRIBER, 1, 0),
                                       ("far", PortKind.SUBSCRIBER, 8, p.SUBSCRIBE_TCP)]:
        plan = registry.plan_port(clients[name], PortRequest(
            kind, "arm.state", "robot/joint_state", 0xABC, 180, buffers, flags))
        if topic is None:
            topic = registry.add_topic(plan)
        if plan.grow_to is not None:
            registry.grow_topic(topic, plan.grow_to)
        registry.add_port(plan, topic)
    local = Rings("", ["/ln.x.1.1", "/ln.x.1.2"])

    async def published(name: str) -> int:
        return 77

    core = SimpleNamespace(registry=registry, local=local, hosts=Hosts(local),
                           segments=SimpleNamespace(names=lambda topic_id: local.names),
                           topic_published=published, services=lambda: [])
    view = SimpleNamespace(stream_listing=lambda: {"streams": streams})
    return Control(core, SimpleNamespace(config=config) if config else None,  # type: ignore[arg-type]
                   network_view=view)  # type: ignore[arg-type]


STREAM = {"topic": "arm.state", "src": "robot_pc", "dst": "vision_pc", "transport": "tcp",
          "msgs_per_s": 1000.0, "bytes_per_s": 180000, "drops": 2, "error": "", "sent": 5}


def test_topic_info_of_a_topic_over_two_hosts() -> None:
    control = control_with_topic([STREAM])
    info = asyncio.run(control.handle({"op": "topic_info", "name": "arm.state"}))
    assert (info["md_name"], info["layout_hash"], info["message_size"], info["slots"],
            info["published"]) == ("robot/joint_state", "0x0000000000000abc", 180, 9, 77)
    assert info["rings"] == [
        {"host": "robot_pc", "segment": "/ln.x.1.2", "generations": ["/ln.x.1.1", "/ln.x.1.2"]},
        {"host": "vision_pc", "segment": "/ln.x.1.1.h2", "generations": ["/ln.x.1.1.h2"]}]
    [pub] = info["publishers"]
    assert (pub["client"], pub["pid"], pub["host"], pub["host_id"],
            pub["wait_for_subscribers"]) == ("pub", 100, "robot_pc", "robot_pc/boot", True)
    near, far = info["subscribers"]
    assert (near["client"], near["mode"], near["reader"], near["transport"], near["asks"]) == (
        "near", "latest", 0, "shm", "")
    assert (far["client"], far["mode"], far["buffers"], far["reader"], far["transport"],
            far["asks"]) == ("far", "queued", 8, 1, "forwarded tcp", "tcp")
    assert info["streams"] == [{k: v for k, v in STREAM.items() if k not in ("topic", "sent")}]
    from links_and_nodes.tools.introspection.values import info_lines

    lines = info_lines(info)
    assert "  far (pid 102, host vision_pc): port 3, queued, 8 buffers, reader 1, forwarded " \
        "tcp" in lines
    assert "  pub (pid 100, host robot_pc): port 1, 1 buffer, waits for subscribers" in lines
    assert lines[-2:] == ["forwarded:", "  robot_pc -> vision_pc over tcp: 1000.0 samples/s, "
                                        "180000 bytes/s, 2 drops"]


def test_a_subscriber_on_another_host_without_a_stream_says_so() -> None:
    info = asyncio.run(control_with_topic([]).handle({"op": "topic_info", "name": "arm.state"}))
    assert info["subscribers"][1]["transport"] == "forwarded (no stream)"


def test_md_dirs_and_md_show_follow_the_configuration(tmp_path: Path) -> None:
    config = SimpleNamespace(message_definition_dirs=[str(OTHER_MDS)],
                             processes={"a": SimpleNamespace(message_definition_dirs=[str(MDS)]),
                                        "b": SimpleNamespace(message_definition_dirs=[])})
    control = control_with_topic([], config)
    shown = asyncio.run(control.handle({"op": "md_show", "name": "lntest/probe"}))
    assert shown["md_dirs"][:2] == [str(OTHER_MDS), str(MDS)]  # the configuration's first
    assert shown["path"] == str(OTHER_MDS / "lntest" / "probe")
    assert shown["mds"] == [{"name": "lntest/probe", "path": shown["path"],
                             "text": (OTHER_MDS / "lntest" / "probe").read_text()}]
    deep = asyncio.run(control.handle({"op": "md_show", "name": "lntest/adjust",
                                       "recursive": True}))
    assert [m["name"] for m in deep["mds"]] == ["lntest/adjust"]  # this one uses none


@pytest.mark.parametrize(("command", "error"), [
    ({"op": "topic_info"}, '"name" must be a non-empty string'),
    ({"op": "topic_info", "name": "nope"}, "no topic 'nope'"),
    ({"op": "service_info", "name": "nope"}, "no service 'nope'"),
    ({"op": "md_show", "name": "lntest/probe", "recursive": 1},
     '"recursive" must be true or false'),
    ({"op": "md_show", "name": "a/../b"}, "message definition name 'a/../b' escapes its "
                                          "directory"),
])
def test_refusals(command: dict[str, Any], error: str) -> None:
    with pytest.raises(ControlError) as info:
        asyncio.run(control_with_topic([]).handle(command))
    assert str(info.value) == error


def test_md_show_recursive_reports_md_errors(tmp_path: Path) -> None:
    broken = tmp_path / "lntest"
    broken.mkdir()
    (broken / "bad").write_text("define x as \"lntest/missing\"\nx field\n")
    config = SimpleNamespace(message_definition_dirs=[str(tmp_path)], processes={})
    control = control_with_topic([], config)
    with pytest.raises(ControlError) as info:
        asyncio.run(control.handle({"op": "md_show", "name": "lntest/bad",
                                    "recursive": True}))
    assert str(info.value).startswith(f"md 'lntest/bad': {broken / 'bad'}:1:")
    assert "lntest/missing" in str(info.value)
