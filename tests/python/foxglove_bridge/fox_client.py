"""A Foxglove WebSocket protocol client for the ln_foxglove tests, written from the protocol's
description on top of the `websockets` package (a test tool, requirements-dev.txt): it
connects with a given subprotocol, collects advertisements, subscribes, decodes message data
frames and calls services.  One client per asyncio task; every wait has an upper bound."""

from __future__ import annotations

import asyncio
import json
import struct
from dataclasses import dataclass, field
from typing import Any

LIMIT = 60.0  # seconds: an upper bound against hangs, never a pass criterion

# binary opcodes
MESSAGE_DATA = 0x01
SERVICE_CALL_RESPONSE = 0x03
SERVICE_CALL_REQUEST = 0x02


@dataclass
class Message:
    subscription: int
    log_time_ns: int
    data: Any  # the decoded JSON


@dataclass
class ServiceReply:
    ok: bool
    data: Any  # the decoded JSON response, or the failure's message text


@dataclass
class FoxClient:
    ws: Any
    server_info: dict[str, Any] = field(default_factory=dict)
    channels: dict[int, dict[str, Any]] = field(default_factory=dict)  # id -> advertised
    services: dict[int, dict[str, Any]] = field(default_factory=dict)
    unadvertised: list[int] = field(default_factory=list)
    unadvertised_services: list[int] = field(default_factory=list)
    statuses: list[dict[str, Any]] = field(default_factory=list)
    messages: list[Message] = field(default_factory=list)
    replies: dict[int, ServiceReply] = field(default_factory=dict)
    # the connection graph as its updates built it: "published", "subscribed", "services",
    # each a name -> set of ids
    graph: dict[str, dict[str, set[str]]] = field(default_factory=lambda: {
        "published": {}, "subscribed": {}, "services": {}})
    graph_updates: int = 0
    _next_call: int = 1

    @property
    def subprotocol(self) -> str | None:
        return self.ws.subprotocol

    def channel(self, topic: str) -> dict[str, Any] | None:
        """The live advertisement of `topic` (the newest, if it came and went)."""
        live = [c for cid, c in self.channels.items()
                if c["topic"] == topic and cid not in self.unadvertised]
        return live[-1] if live else None

    def service(self, name: str) -> dict[str, Any] | None:
        live = [s for sid, s in self.services.items()
                if s["name"] == name and sid not in self.unadvertised_services]
        return live[-1] if live else None

    # ---- receiving ---------------------------------------------------------------------------
    def _take(self, frame: str | bytes) -> None:
        if isinstance(frame, bytes):
            op = frame[0]
            if op == MESSAGE_DATA:
                sub, t_ns = struct.unpack_from("<IQ", frame, 1)
                self.messages.append(Message(sub, t_ns, json.loads(frame[13:])))
            elif op == SERVICE_CALL_RESPONSE:
                _sid, call, n = struct.unpack_from("<III", frame, 1)
                assert frame[13:13 + n] == b"json", frame[:40]
                self.replies[call] = ServiceReply(True, json.loads(frame[13 + n:]))
            return
        msg = json.loads(frame)
        op = msg["op"]
        if op == "serverInfo":
            self.server_info = msg
        elif op == "advertise":
            for c in msg["channels"]:
                self.channels[c["id"]] = c
        elif op == "unadvertise":
            self.unadvertised += msg["channelIds"]
        elif op == "advertiseServices":
            for s in msg["services"]:
                self.services[s["id"]] = s
        elif op == "unadvertiseServices":
            self.unadvertised_services += msg["serviceIds"]
        elif op == "serviceCallFailure":
            self.replies[msg["callId"]] = ServiceReply(False, msg["message"])
        elif op == "status":
            self.statuses.append(msg)
        elif op == "connectionGraphUpdate":
            self._graph_update(msg)

    def _graph_update(self, msg: dict[str, Any]) -> None:
        g = self.graph
        for key, field_name, ids in (("published", "publishedTopics", "publisherIds"),
                                     ("subscribed", "subscribedTopics", "subscriberIds"),
                                     ("services", "advertisedServices", "providerIds")):
            for entry in msg.get(field_name, []):
                g[key][entry["name"]] = set(entry[ids])
        for name in msg.get("removedTopics", []):
            g["published"].pop(name, None)
            g["subscribed"].pop(name, None)
        for name in msg.get("removedServices", []):
            g["services"].pop(name, None)
        self.graph_updates += 1

    async def until(self, predicate: Any, what: str, timeout: float = LIMIT) -> Any:
        """Receive until `predicate()` is true; its value.  AssertionError after `timeout`."""
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        while not (value := predicate()):
            left = deadline - loop.time()
            if left <= 0:
                raise AssertionError(f"gave up waiting for {what}")
            try:
                self._take(await asyncio.wait_for(self.ws.recv(), left))
            except TimeoutError:
                continue
        return value

    # ---- sending -----------------------------------------------------------------------------
    async def subscribe(self, subscription: int, channel_id: int) -> None:
        await self.ws.send(json.dumps({"op": "subscribe", "subscriptions": [
            {"id": subscription, "channelId": channel_id}]}))

    async def subscribe_graph(self) -> None:
        await self.ws.send(json.dumps({"op": "subscribeConnectionGraph"}))

    async def unsubscribe(self, subscription: int) -> None:
        await self.ws.send(json.dumps({"op": "unsubscribe", "subscriptionIds": [subscription]}))

    async def call(self, service_id: int, request: Any, encoding: str = "json",
                   raw: bytes | None = None) -> ServiceReply:
        call = self._next_call
        self._next_call += 1
        payload = raw if raw is not None else json.dumps(request).encode()
        enc = encoding.encode()
        await self.ws.send(struct.pack("<BIII", SERVICE_CALL_REQUEST, service_id, call,
                                       len(enc)) + enc + payload)
        return await self.until(lambda: self.replies.get(call), f"the answer to call {call}")


async def connect(port: int, subprotocol: str) -> FoxClient:
    """A client connected with `subprotocol` that has the server's info and first
    advertisements."""
    from websockets.asyncio.client import connect as ws_connect

    ws = await ws_connect(f"ws://127.0.0.1:{port}", subprotocols=[subprotocol],
                          max_size=None, max_queue=None, open_timeout=LIMIT)
    client = FoxClient(ws)
    await client.until(lambda: client.server_info, "serverInfo")
    return client
