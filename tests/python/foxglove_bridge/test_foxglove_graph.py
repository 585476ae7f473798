"""ln_foxglove's connection graph (the protocol's connectionGraph capability): a client that
sends subscribeConnectionGraph gets the system's published topics with their publishers and
its services with their providers (the processes of conftest.py's configuration), and the
bridge's own subscription shows up while a client reads a channel and goes when it stops.
The pure mapping from the manager's `graph` answer is checked on its own."""

from __future__ import annotations

import asyncio

from links_and_nodes.foxglove_bridge.graph import connection_graph

from .conftest import System
from .fox_client import FoxClient, connect
from .test_foxglove_live import receive

PUBLISHED = {"fx.joint": {"pub"}, "fx.fast": {"fast"}, "fx.probe": {"probe"}}


def published(client: FoxClient) -> dict[str, set[str]]:
    """The topics with publishers in the client's graph."""
    return {name: ids for name, ids in client.graph["published"].items() if ids}


def test_connection_graph_follows_the_system(system: System) -> None:
    async def run() -> None:
        client = await connect(system.foxglove_port, "foxglove.websocket.v1")
        async with client.ws:
            assert "connectionGraph" in client.server_info["capabilities"]
            await client.subscribe_graph()
            await client.until(lambda: published(client) == PUBLISHED
                               and client.graph["services"] == {"fx.gains": {"gains"}},
                               "the published topics and the service in the graph")
            assert not client.graph["subscribed"].get("fx.probe")
            await receive(client, "fx.probe", 1, sub=3)
            await client.until(
                lambda: client.graph["subscribed"].get("fx.probe") == {"foxglove"},
                "the bridge as the subscriber of fx.probe")
            await client.unsubscribe(3)
            await client.until(lambda: not client.graph["subscribed"].get("fx.probe"),
                               "the bridge's subscription gone from the graph")
            assert published(client) == PUBLISHED

    asyncio.run(run())


def test_connection_graph_of_a_graph_answer() -> None:
    answer = {"nodes": [{"id": "p:a/pub", "kind": "process", "name": "a/pub"},
                        {"id": "c:sub", "kind": "client", "name": "sub"},
                        {"id": "t:x", "kind": "topic", "name": "x"},
                        {"id": "t:idle", "kind": "topic", "name": "idle"},
                        {"id": "s:svc", "kind": "service", "name": "svc"}],
              "edges": [{"from": "p:a/pub", "to": "t:x", "kind": "publishes"},
                        {"from": "t:x", "to": "c:sub", "kind": "subscribes"},
                        {"from": "t:x", "to": "p:a/pub", "kind": "subscribes"},
                        {"from": "s:svc", "to": "p:a/pub", "kind": "provides"},
                        {"from": "c:sub", "to": "s:svc", "kind": "calls"},
                        {"from": "p:a/pub", "to": "c:sub", "kind": "depends_on"}]}
    published, subscribed, services = connection_graph(answer)
    assert published == {"x": {"a/pub"}, "idle": set()}
    assert subscribed == {"x": {"sub", "a/pub"}, "idle": set()}
    assert services == {"svc": {"a/pub"}}
