"""The Foxglove connection graph (the protocol's `connectionGraph` capability:
subscribeConnectionGraph / connectionGraphUpdate) from the manager's `graph` command:
published topics with their publishers, subscribed topics with their subscribers,
advertised services with their providers; a publisher, subscriber or provider is named as
the graph names its node (a process of the configuration, else the client).  Pure but for
`ConnectionGraphFeed.publish`, which the bridge's poll calls while a client subscribes."""

from __future__ import annotations

import threading
from typing import Any

Sets = dict[str, frozenset[str]]


def connection_graph(answer: dict[str, Any]) -> tuple[Sets, Sets, Sets]:
    """(published topics, subscribed topics, advertised services): name -> node names
    (empty for a topic nobody publishes or subscribes now)."""
    names = {n["id"]: n["name"] for n in answer["nodes"]}
    published: dict[str, set[str]] = {}
    subscribed: dict[str, set[str]] = {}
    services: dict[str, set[str]] = {}
    for node in answer["nodes"]:
        if node["kind"] == "topic":
            published.setdefault(node["name"], set())
            subscribed.setdefault(node["name"], set())
        elif node["kind"] == "service":
            services.setdefault(node["name"], set())
    for e in answer["edges"]:
        src, dst = names.get(e["from"], e["from"]), names.get(e["to"], e["to"])
        if e["kind"] == "publishes":
            published.setdefault(dst, set()).add(src)
        elif e["kind"] == "subscribes":
            subscribed.setdefault(src, set()).add(dst)
        elif e["kind"] == "provides":
            services.setdefault(src, set()).add(dst)

    # every topic and service stays, with no ids when nobody is left: the sdk sends the
    # difference to the last graph, and a name left out would keep its old ids at the client
    def frozen(d: dict[str, set[str]]) -> Sets:
        return {k: frozenset(v) for k, v in d.items()}

    return frozen(published), frozen(subscribed), frozen(services)


class ConnectionGraphFeed:
    """Follows the clients' subscriptions to the graph (the sdk's listener calls) and
    publishes the manager's graph while there are any, only when it changed."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._subscribed = False
        self._last: tuple[Sets, Sets, Sets] | None = None
        self.published = 0  # updates handed to the sdk

    def subscribe(self) -> None:
        with self._lock:
            self._subscribed = True
            self._last = None  # a new client: publish at the next poll

    def unsubscribe(self) -> None:
        with self._lock:
            self._subscribed = False

    @property
    def wanted(self) -> bool:
        with self._lock:
            return self._subscribed

    def publish(self, server: Any, answer: dict[str, Any]) -> bool:
        """Hand the graph to the sdk if it differs from the last one; whether it did."""
        from foxglove.websocket import ConnectionGraph

        sets = connection_graph(answer)
        with self._lock:
            if sets == self._last:
                return False
            self._last = sets
        graph = ConnectionGraph()
        published, subscribed, services = sets
        for topic, ids in published.items():
            graph.set_published_topic(topic, sorted(ids))
        for topic, ids in subscribed.items():
            graph.set_subscribed_topic(topic, sorted(ids))
        for service, ids in services.items():
            graph.set_advertised_service(service, sorted(ids))
        server.publish_connection_graph(graph)
        self.published += 1
        return True
