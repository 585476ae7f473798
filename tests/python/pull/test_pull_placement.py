"""The manager's placement of pull topics (manager/network/pull.py) against a fake registry and a
fake daemon link: which topics go to the daemon with which settings, a refusal kept in the
status and retried, re-placement on a new ring or a reloaded setting, removal when the
publisher leaves, and the removal of everything on close."""

from __future__ import annotations

import asyncio
from pathlib import Path
from typing import Any

from links_and_nodes.manager.config import load
from links_and_nodes.manager.network import daemon_pull as dp
from links_and_nodes.manager.network.pull import PullTopics
from links_and_nodes.manager.processes import daemon_wire as dw
from links_and_nodes.manager.registry.model import Client, Port, PortKind, Topic


class FakeRings:
    def __init__(self) -> None:
        self.segments: dict[int, str] = {}

    def has(self, topic_id: int) -> bool:
        return topic_id in self.segments

    def current(self, topic_id: int) -> str:
        return self.segments[topic_id]


class FakeRegistry:
    def __init__(self) -> None:
        self.topics: dict[str, Topic] = {}


class FakeCore:
    def __init__(self) -> None:
        self.registry = FakeRegistry()
        self.local = FakeRings()
        self.hosts = None
        self.listeners: list[Any] = []

    def publish(self, name: str, topic_id: int, ring: str) -> Topic:
        topic = Topic(topic_id, name, "robot/joint_state", 0xABC, 172, 2)
        client = Client(topic_id, "pub", 1, "", "1")
        topic.ports[1] = Port(1, client, PortKind.PUBLISHER, topic, topic.md_name, 1, 0, None)
        self.registry.topics[name] = topic
        self.local.segments[topic_id] = ring
        return topic


class FakeLink:
    def __init__(self) -> None:
        self.calls: list[tuple[str, tuple[Any, ...]]] = []
        self.refuse: list[str] = []  # texts of the next refusals

    async def pull_topic(self, *args: Any) -> None:
        self.calls.append(("topic", args))
        if self.refuse:
            raise dw.DaemonError(self.refuse.pop(0), dw.ErrorCode.LOGGER_FAILED)

    async def pull_remove(self, topic: str) -> None:
        self.calls.append(("remove", (topic,)))

    async def pull_status(self, topic: str = "") -> dp.PullStatus:
        served = {args[0]: args for kind, args in self.calls if kind == "topic"}
        return dp.PullStatus([dp.PullPortStatus("", 6363, 5, 1, 1, 1, "")], [
            dp.PullTopicStatus(t, a[7], a[1], a[5], a[6], a[8], 3, 4, 1, 3, 0, 0, 0, 0, 0, "")
            for t, a in served.items()])


def config(tmp_path: Path, topics: str) -> Any:
    path = tmp_path / "m.lnc"
    path.write_text("instance\nname: lab\nmanager: :54414\ntopics\n" + topics)
    return load(path, env={})


async def test_placement_follows_publishers_settings_and_refusals(tmp_path: Path) -> None:
    core, link = FakeCore(), FakeLink()

    async def local_link() -> FakeLink:
        return link

    pulls = PullTopics(core, config(tmp_path, "arm.*: pull:ndn-udp, pull_key:0102\n"),
                       local_link, lambda: "here")  # type: ignore[arg-type]
    core.publish("arm.state", 1, "ring-a")
    core.publish("other", 2, "ring-o")
    link.refuse = ["port 6363 in use"]
    await pulls.apply()
    assert link.calls == [("topic", ("arm.state", "ring-a", "robot/joint_state", 0xABC, 172,
                                     "0.0.0.0", 6363, "/ln/lab/arm.state", 64, 1000,
                                     b"\x01\x02"))]
    status = await pulls.status()
    assert status[0]["topics"][0]["error"] == "port 6363 in use"
    assert pulls.listing()[0]["error"] == "port 6363 in use"
    await pulls.apply()  # retried
    assert len(link.calls) == 2 and not pulls.listing()[0]["error"]
    assert pulls.listing()[0]["signature"] == "HMAC-SHA256"
    await pulls.apply()  # nothing changed: not sent again
    assert len(link.calls) == 2
    core.local.segments[1] = "ring-a2"  # the ring grew
    await pulls.apply()
    assert link.calls[-1][1][1] == "ring-a2"
    pulls.configure(config(tmp_path, "arm.*: pull:ndn-udp, pull_port:7000\n"))
    await pulls.apply()
    assert link.calls[-1][1][6] == 7000 and link.calls[-1][1][10] == b""
    status = await pulls.status()
    assert status[0]["ports"][0]["packets"] == 5
    assert status[0]["topics"][0]["name"] == "/ln/lab/arm.state"
    del core.registry.topics["arm.state"]  # the publisher left
    await pulls.apply()
    assert link.calls[-1] == ("remove", ("arm.state",)) and pulls.listing() == []
    core.publish("arm.x", 3, "ring-x")
    await pulls.apply()
    await pulls.close(remove=True)
    assert link.calls[-1] == ("remove", ("",))


async def test_follows_the_registry_and_retries_by_itself(tmp_path: Path) -> None:
    core, link = FakeCore(), FakeLink()

    async def local_link() -> FakeLink:
        return link

    pulls = PullTopics(core, config(tmp_path, "t: pull:ndn-udp\n"), local_link,
                       lambda: "here")  # type: ignore[arg-type]
    link.refuse = ["busy"]
    pulls.start()
    core.publish("t", 1, "r")
    for listener in core.listeners:
        listener()
    for _ in range(400):  # the retry comes after RETRY_S
        if len(link.calls) >= 2:
            break
        await asyncio.sleep(0.01)
    assert [c[0] for c in link.calls] == ["topic", "topic"]
    await pulls.close(remove=False)  # detaching: left served
    assert link.calls[-1][0] == "topic"
