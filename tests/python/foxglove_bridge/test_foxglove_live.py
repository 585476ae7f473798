"""ln_foxglove against a running system (conftest.py): both subprotocols, channels and
services with their JSON Schemas, samples equal to what the C and Python publishers wrote and
in their order, subscribing only while a client subscribes, the rate limit, service calls and
their failures, topics and services that go away, and bad client messages."""

from __future__ import annotations

import asyncio
import json
import socket
import statistics
from itertools import pairwise
from typing import Any

import pytest

from .conftest import FAST_RATE, LIMIT, QUEUE, System, wait_for
from .fox_client import FoxClient, connect
from .schema_check import conforms

SUBPROTOCOLS = ["foxglove.websocket.v1", "foxglove.sdk.v1"]


def joint_state(i: int) -> dict[str, Any]:
    """What topic_tool's fill_joint(i) writes (every value exact in binary but timestamp,
    which is the same double operation here)."""
    return {"timestamp": i * 0.001, "cycle": i,
            "position": [i + j / 8.0 for j in range(7)],
            "velocity": [-i - j / 4.0 for j in range(7)],
            "effort": [float(i * j) for j in range(7)]}


def probe(k: int) -> dict[str, Any]:
    """What tests/python/introspection/probe_publisher.py writes as sample k."""
    return {"count": k, "q": [k + j / 8 for j in range(7)],
            "target": {"position": [float(k), 2.0 * k, 3.0 * k],
                       "orientation": [0.0, 0.0, 0.0, 1.0]},
            "gains": [0.1, 0.2, 0.3], "label": "probe",
            "trace": [float(k * 1000 + i) for i in range(100)]}


async def channel(client: FoxClient, topic: str) -> dict[str, Any]:
    return await client.until(lambda: client.channel(topic), f"channel {topic}")


async def service(client: FoxClient, name: str) -> dict[str, Any]:
    return await client.until(lambda: client.service(name), f"service {name}")


async def receive(client: FoxClient, topic: str, n: int, sub: int = 1) -> list[Any]:
    """Subscribe to `topic` and return the first `n` messages."""
    ch = await channel(client, topic)
    await client.subscribe(sub, ch["id"])
    await client.until(lambda: sum(m.subscription == sub for m in client.messages) >= n,
                       f"{n} messages of {topic}")
    return [m for m in client.messages if m.subscription == sub][:n]


def bridge_readers(system: System, topic: str) -> list[dict[str, Any]]:
    """The subscriptions of the ln_foxglove process to `topic`."""
    with system.connect() as mgr:
        pid = next(p["pid"] for p in mgr.status() if p["name"] == "foxglove")
        info = mgr.command("topic_info", name=topic)
    return [s for s in info["subscribers"] if s["pid"] == pid]


@pytest.mark.parametrize("subprotocol", SUBPROTOCOLS)
def test_each_subprotocol_lists_channels_and_services(system: System, subprotocol: str
                                                      ) -> None:
    async def run() -> None:
        client = await connect(system.foxglove_port, subprotocol)
        async with client.ws:
            assert client.subprotocol == subprotocol
            assert client.server_info["name"] == f"links_and_nodes {system.instance}"
            assert "services" in client.server_info["capabilities"]
            joint = await channel(client, "fx.joint")
            assert (joint["encoding"], joint["schemaName"], joint["schemaEncoding"]) == \
                ("json", "robot/joint_state", "jsonschema")
            schema = json.loads(joint["schema"])
            assert schema["properties"]["position"] == {
                "type": "array", "items": {"type": "number"}, "minItems": 7, "maxItems": 7,
                "description": "rad"}
            assert schema["properties"]["cycle"]["type"] == "integer"
            assert joint["metadata"]["mode"] == f"queued {QUEUE}"
            assert (await channel(client, "fx.fast"))["metadata"]["rate"] == str(FAST_RATE)
            probe_schema = json.loads((await channel(client, "fx.probe"))["schema"])
            assert probe_schema["properties"]["label"] == {"type": "string", "maxLength": 8,
                                                           "description": '"probe"'}
            assert probe_schema["properties"]["target"]["type"] == "object"
            gains = await service(client, "fx.gains")
            assert gains["type"] == "robot/set_gains"
            request = json.loads(gains["request"]["schema"])
            assert request["properties"]["profile_name"]["type"] == "string"
            assert request["properties"]["kp"]["maxItems"] == 7
            response = json.loads(gains["response"]["schema"])
            assert response["required"] == ["ok", "message"]

    asyncio.run(run())


def test_other_subprotocols_are_refused(system: System) -> None:
    from websockets.exceptions import InvalidStatus

    async def run() -> None:
        with pytest.raises(InvalidStatus):
            await connect(system.foxglove_port, "foxglove.websocket.v2")

    asyncio.run(run())


def test_c_samples_arrive_equal_and_in_order(system: System) -> None:
    async def run() -> None:
        client = await connect(system.foxglove_port, "foxglove.websocket.v1")
        async with client.ws:
            schema = json.loads((await channel(client, "fx.joint"))["schema"])
            messages = await receive(client, "fx.joint", 200)
        cycles = [m.data["cycle"] for m in messages]
        assert all(a < b for a, b in pairwise(cycles)), cycles
        for m in messages:
            assert m.data == joint_state(m.data["cycle"])
            assert conforms(m.data, schema)
        times = [m.log_time_ns for m in messages]  # publish times
        assert all(a < b for a, b in pairwise(times))

    asyncio.run(run())


def test_nested_float32_and_char_fields(system: System) -> None:
    async def run() -> None:
        client = await connect(system.foxglove_port, "foxglove.sdk.v1")
        async with client.ws:
            schema = json.loads((await channel(client, "fx.probe"))["schema"])
            messages = await receive(client, "fx.probe", 5)
        counts = [m.data["count"] for m in messages]
        assert all(a < b for a, b in pairwise(counts)), counts
        for m in messages:
            assert m.data == probe(m.data["count"])  # gains: 0.1 as float32 shows as 0.1
            assert conforms(m.data, schema)

    asyncio.run(run())


def test_reads_only_while_a_client_subscribes(system: System) -> None:
    async def run() -> None:
        first = await connect(system.foxglove_port, "foxglove.sdk.v1")
        second = await connect(system.foxglove_port, "foxglove.websocket.v1")
        async with first.ws, second.ws:
            ch = await channel(first, "fx.probe")
            await channel(second, "fx.probe")
            # none left from an earlier test's client
            await asyncio.to_thread(wait_for, lambda: not bridge_readers(system, "fx.probe"),
                                    "no reader of fx.probe")
            await receive(first, "fx.probe", 1, sub=5)
            await receive(second, "fx.probe", 1, sub=6)
            readers = bridge_readers(system, "fx.probe")
            assert len(readers) == 1 and readers[0]["mode"] == "latest"
            await first.unsubscribe(5)
            await asyncio.sleep(0.5)  # a chance to stop wrongly: the second still reads
            assert len(bridge_readers(system, "fx.probe")) == 1
            n = len(second.messages)
            await second.until(lambda: len(second.messages) > n + 3, "more for the second")
            await second.unsubscribe(6)
            await asyncio.to_thread(wait_for, lambda: not bridge_readers(system, "fx.probe"),
                                    "the bridge to unsubscribe")
            # subscribing again reads again (the same channel)
            await first.subscribe(7, ch["id"])
            await first.until(lambda: any(m.subscription == 7 for m in first.messages),
                              "messages after subscribing again")
            await first.unsubscribe(7)
        await asyncio.to_thread(wait_for, lambda: not bridge_readers(system, "fx.probe"),
                                "the bridge to unsubscribe after the clients left")

    asyncio.run(run())


def test_rate_limit_per_channel(system: System) -> None:
    async def run() -> None:
        client = await connect(system.foxglove_port, "foxglove.sdk.v1")
        async with client.ws:
            fast = await receive(client, "fx.fast", 6, sub=1)
            joint = await receive(client, "fx.joint", 6, sub=2)
        # both topics come from the same 1 kHz publisher program: fx.joint (queued) skips
        # nothing the bridge keeps up with, fx.fast (at most 10 Hz) about 100 cycles a time
        gaps = [b.data["cycle"] - a.data["cycle"] for a, b in pairwise(fast)]
        joint_gaps = [b.data["cycle"] - a.data["cycle"] for a, b in pairwise(joint)]
        assert statistics.median(gaps) >= 10 * statistics.median(joint_gaps), (gaps,
                                                                               joint_gaps)

    asyncio.run(run())


def test_service_calls_and_failures(system: System) -> None:
    async def run() -> None:
        client = await connect(system.foxglove_port, "foxglove.websocket.v1")
        async with client.ws:
            sid = (await service(client, "fx.gains"))["id"]
            reply = await client.call(sid, {"kp": [1.5] * 7, "kd": [0.25] * 7,
                                            "profile_name": "soft"})
            assert reply.ok and reply.data == {"ok": 1,
                                               "message": "soft: kp sum 10.5, kd sum 1.75"}
            bad = await client.call(sid, {"kp": [1.0] * 7, "stiffness": 3})
            assert not bad.ok and "stiffness" in bad.data, bad
            short = await client.call(sid, {"kp": [1.0] * 3})
            assert not short.ok and "kp" in short.data, short
            not_json = await client.call(sid, None, raw=b"{kp: ")
            assert not not_json.ok and "bad request" in not_json.data, not_json
            not_object = await client.call(sid, [1, 2])
            assert not not_object.ok and "JSON object" in not_object.data, not_object
            other = await client.call(sid, {}, encoding="cbor")
            assert not other.ok, other
            again = await client.call(sid, {"profile_name": "after"})
            assert again.ok and again.data["message"] == "after: kp sum 0, kd sum 0"

    asyncio.run(run())


def test_topics_and_services_that_go_are_unadvertised(system: System) -> None:
    async def run() -> None:
        client = await connect(system.foxglove_port, "foxglove.sdk.v1")
        async with client.ws:
            old = (await channel(client, "fx.fast"))["id"]
            old_service = (await service(client, "fx.gains"))["id"]
            with system.connect() as mgr:
                await asyncio.to_thread(mgr.stop, "fast")
                await asyncio.to_thread(mgr.stop, "gains")
            await client.until(lambda: old in client.unadvertised, "fx.fast unadvertised")
            await client.until(lambda: old_service in client.unadvertised_services,
                               "fx.gains unadvertised")
            assert client.channel("fx.joint") is not None  # the others stay
            with system.connect() as mgr:
                mgr.start("fast")
                mgr.start("gains")
                await asyncio.to_thread(mgr.wait_ready, "all", LIMIT)
            new = await channel(client, "fx.fast")
            assert new["id"] != old
            sid = (await service(client, "fx.gains"))["id"]
            assert sid != old_service
            assert (await client.call(sid, {"profile_name": "back"})).ok
            assert len(await receive(client, "fx.fast", 2, sub=9)) == 2

    asyncio.run(run())


def test_bad_client_messages_do_not_kill_the_bridge(system: System) -> None:
    garbage: list[str | bytes] = [
        "not json", "{}", '{"op": "nonsense"}', '{"op": "subscribe"}',
        '{"op": "subscribe", "subscriptions": [{"id": 1, "channelId": 999999}]}',
        '{"op": "subscribe", "subscriptions": [{"id": "x", "channelId": []}]}',
        '{"op": "unsubscribe", "subscriptionIds": [424242]}',
        b"", b"\xff\x00", b"\x02\x01", b"\x02" + bytes(12),
        b"\x02\x09\x00\x00\x00\x01\x00\x00\x00\xff\xff\xff\xffjson",
        '{"op": "advertise", "channels": [{"id": 1, "topic": "x"}]}',
        '{"op": "getParameters", "parameterNames": ["a"]}',
    ]

    async def run() -> None:
        client = await connect(system.foxglove_port, "foxglove.websocket.v1")
        async with client.ws:
            for frame in garbage:
                await client.ws.send(frame)
            await client.until(lambda: len(client.statuses) >= 3, "status messages")
        await asyncio.to_thread(_raw_garbage, system.foxglove_port)
        # the bridge lives on and serves a new client
        client = await connect(system.foxglove_port, "foxglove.sdk.v1")
        async with client.ws:
            assert len(await receive(client, "fx.probe", 2)) == 2
            sid = (await service(client, "fx.gains"))["id"]
            assert (await client.call(sid, {"profile_name": "fine"})).ok

    asyncio.run(run())
    with system.connect() as mgr:
        assert mgr.state("foxglove") == "ready"


def _raw_garbage(port: int) -> None:
    """Connections to the front that are no WebSocket handshakes."""
    for data in [b"\x00\x01binary nonsense\r\n\r\n", b"GET / HTTP/1.1\r\nHost: x\r\n\r\n",
                 b"GET / HTTP/1.1\r\n" + b"X-Long: " + b"a" * 100_000 + b"\r\n\r\n", b""]:
        with socket.create_connection(("127.0.0.1", port), timeout=LIMIT) as s:
            try:
                s.sendall(data)
                s.shutdown(socket.SHUT_WR)
                while s.recv(4096):
                    pass
            except ConnectionError:
                pass  # the front closed it before taking all: what it should do
