"""The bridge: the Foxglove server (foxglove-sdk) with one channel per links_and_nodes topic
and one service per links_and_nodes service, following the manager's lists.

`start()` connects to the manager, starts the sdk's server (with its own sdk Context) and, in
front of it, the subprotocol front (front.py); `poll()` takes the manager's topic and service
lists: a topic with a publisher that the rules select becomes a channel, a service a Foxglove
service; a topic without publishers or gone, or a service gone, is unadvertised.  The sdk calls
on_subscribe/on_unsubscribe (ServerListener) from its threads: a channel reads its topic while
at least one client subscribes.  The lock guards the dicts only; sdk calls are made without it,
as the sdk may call back into the listener from within them.  While a client subscribes to
the connection graph, `poll()` also publishes the manager's `graph` when it changed (graph.py).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from ..tools.introspection.client import load_md
from ..tools.introspection.commands import CommandError, topic_layout
from .config import FoxgloveConfig
from .front import LEGACY, SDK, Front
from .graph import ConnectionGraphFeed
from .link import ManagerLink
from .log_feed import LogFeed
from .services import BridgedService
from .topics import TopicChannel

RETRY = 5.0  # seconds before a topic or service that could not be bridged is tried again


class Bridge:
    def __init__(self, config: FoxgloveConfig, address: str,
                 say: Callable[[str], None]) -> None:
        self.config = config
        self.address = address
        self._say = say
        self.link: Any = None
        self.context: Any = None
        self.server: Any = None
        self.front: Front | None = None
        self.port = 0
        self.topics: dict[str, TopicChannel] = {}
        self.services: dict[str, BridgedService] = {}
        self._by_id: dict[int, TopicChannel] = {}
        self._early: dict[int, set[int]] = {}  # channel id -> clients, before it is known here
        self._lock = threading.Lock()
        self._failed: dict[str, float] = {}  # "kind:name" -> when it may be tried again
        self._reasons: dict[str, str] = {}
        self._listing_error: str | None = None
        self.graph = ConnectionGraphFeed()
        self.logs: LogFeed | None = None  # the ln.log channel (log_feed.py), from start()
        self._graph_error: str | None = None

    def say(self, text: str, verbose: bool = False) -> None:
        if self.config.verbose or not verbose:
            self._say(text)

    def warn(self, text: str) -> None:
        """Said, and shown to the Foxglove clients as a warning."""
        import foxglove

        self._say(text)
        server = self.server
        if server is not None:
            server.publish_status(text, foxglove.StatusLevel.Warning)

    # ---- start and stop --------------------------------------------------------------------
    def start(self) -> None:
        import foxglove
        from foxglove.websocket import Capability

        self.link = ManagerLink(self.address, self.config.name)
        self.context = foxglove.Context()
        direct = self.config.direct
        self.server = foxglove.start_server(
            name=f"links_and_nodes {self.link.instance}",
            host=self.config.host if direct else "127.0.0.1",
            port=self.config.port if direct else 0,
            capabilities=[Capability.ConnectionGraph]
            + ([Capability.Services] if self.config.offer_services else []),
            supported_encodings=["json"], server_listener=self, context=self.context)
        self.logs = LogFeed(self.context)
        # where the manager's log is now: lines after this (and after "serving") go out
        self.logs.poll(self.link.control, self.say)
        if direct:
            self.port = self.server.port
            protocols = SDK
        else:
            self.front = Front(self.config.host, self.config.port, self.server.port, self._say,
                               self.config.origins)
            self.port = self.front.port
            protocols = f"{LEGACY} and {SDK}"
        self.say(f"serving ws://{self.config.host}:{self.port} ({protocols}) for instance "
                 f"'{self.link.instance}'")

    def close(self) -> None:
        with self._lock:
            topics = list(self.topics.values())
            self.topics.clear()
            self._by_id.clear()
        for topic in topics:
            topic.close()
        if self.front is not None:
            self.front.close()
        if self.server is not None:
            self.server.stop()
        if self.link is not None:
            self.link.close()

    # ---- the sdk's ServerListener ----------------------------------------------------------
    def on_subscribe(self, client: Any, channel: Any) -> None:
        with self._lock:
            topic = self._by_id.get(channel.id)
            if topic is None:
                self._early.setdefault(channel.id, set()).add(client.id)
            else:
                topic.subscribe(client.id)

    def on_unsubscribe(self, client: Any, channel: Any) -> None:
        with self._lock:
            topic = self._by_id.get(channel.id)
            if topic is None:
                self._early.get(channel.id, set()).discard(client.id)
            else:
                topic.unsubscribe(client.id)

    def on_connection_graph_subscribe(self) -> None:
        self.graph.subscribe()  # published by the next poll: never from within this call

    def on_connection_graph_unsubscribe(self) -> None:
        self.graph.unsubscribe()

    # ---- following the manager -------------------------------------------------------------
    def poll(self) -> None:
        """Advertise what appeared in the manager's lists, unadvertise what went."""
        try:
            topics = self.link.control("topics")["topics"]
            services = self.link.control("services")["services"] \
                if self.config.offer_services else []
        except CommandError as exc:
            if str(exc) != self._listing_error:
                self._listing_error = str(exc)
                self.say(f"cannot list the manager's topics and services (will retry): {exc}")
            return
        if self._listing_error is not None:
            self._listing_error = None
            self.say("the manager answers again")
        now = time.monotonic()
        self._follow_topics({str(t["name"]): t for t in topics
                             if t.get("md_name") and int(t.get("publishers", 0)) > 0}, now)
        self._follow_services({str(s["name"]): s for s in services if s.get("md_name")}, now)
        if self.graph.wanted:
            self._publish_graph()
        if self.logs is not None:
            self.logs.poll(self.link.control, self.say)

    def _publish_graph(self) -> None:
        try:
            answer = self.link.control("graph", window=0)
        except CommandError as exc:
            if str(exc) != self._graph_error:  # said once per reason
                self._graph_error = str(exc)
                self.warn(f"cannot get the manager's graph (no connection graph): {exc}")
            return
        self._graph_error = None
        if self.graph.publish(self.server, answer):
            self.say("connection graph updated", verbose=True)

    def _follow_topics(self, present: dict[str, dict[str, Any]], now: float) -> None:
        with self._lock:
            gone = [t for name, t in self.topics.items()
                    if name not in present or present[name]["md_name"] != t.md_name
                    or t.stale]
            for topic in gone:
                del self.topics[topic.name]
                self._by_id.pop(topic.id, None)
        for topic in gone:
            topic.close()
            with self._lock:
                self._early.pop(topic.id, None)  # a subscribe that came while it went
            self.say(f"topic '{topic.name}' is gone (or has no publisher): unadvertised")
        for name in sorted(present):
            if name in self.topics or self._failed.get(f"topic:{name}", 0.0) > now:
                continue
            rule = self.config.topic_rule(name)
            if rule is None:
                continue
            try:
                info = self.link.control("topic_info", name=name)
                md = topic_layout(info)
                topic = TopicChannel(self, info, md, rule)
            except Exception as exc:  # noqa: BLE001 - CommandError, an sdk refusal
                self._give_up("topic", name, str(exc), now)
                continue
            with self._lock:
                self.topics[name] = topic
                self._by_id[topic.id] = topic
                for client_id in self._early.pop(topic.id, set()):
                    topic.subscribe(client_id)
            self.say(f"topic '{name}' ({md.name}): advertised as channel {topic.id}")

    def _follow_services(self, present: dict[str, dict[str, Any]], now: float) -> None:
        gone = [s for name, s in self.services.items()
                if name not in present
                or (present[name]["md_name"], int(present[name].get("layout_hash", 0)))
                != (s.md_name, s.layout_hash)]
        if gone:
            for service in gone:
                del self.services[service.name]
            self.server.remove_services([s.name for s in gone])
            for service in gone:
                self.say(f"service '{service.name}' is gone: unadvertised")
        added = []
        for name in sorted(present):
            if name in self.services or self._failed.get(f"service:{name}", 0.0) > now:
                continue
            rule = self.config.service_rule(name)
            if rule is None:
                continue
            try:
                info = self.link.control("service_info", name=name)
                md = load_md(str(info["md_name"]), list(info["md_dirs"]))
                if md.kind != "service":
                    raise CommandError(f"its md {md.name!r} is a {md.kind}, not a service")
                if md.layout_hash != int(info["layout_hash"], 16):
                    raise CommandError(
                        f"layout mismatch: md {md.name!r} found here ({md.path}) has hash "
                        f"0x{md.layout_hash:016x}, the provider registered "
                        f"{info['layout_hash']}")
                service = BridgedService(self, info, md, rule)
            except Exception as exc:  # noqa: BLE001 - CommandError, IntrospectError
                self._give_up("service", name, str(exc), now)
                continue
            self.services[name] = service
            added.append(service)
        if added:
            self.server.add_services([s.service for s in added])
            for service in added:
                self.say(f"service '{service.name}' ({service.md_name}): advertised")

    def _give_up(self, kind: str, name: str, why: str, now: float) -> None:
        key = f"{kind}:{name}"
        self._failed[key] = now + RETRY
        if self._reasons.get(key) != why:  # said once per reason, not every retry
            self._reasons[key] = why
            self.say(f"{kind} '{name}' is not bridged (tried again every {RETRY:g} s): {why}")

    # ---- statistics --------------------------------------------------------------------------
    def stats_lines(self) -> list[str]:
        with self._lock:
            topics = sorted(self.topics.values(), key=lambda t: t.name)
        lines = [f"topic '{t.name}': {len(t.clients)} subscribed clients, read {t.stats.read}, "
                 f"sent {t.stats.sent}, rate-limited {t.stats.rate_limited}, "
                 f"errors {t.stats.errors}" for t in topics]
        lines += [f"service '{s.name}': {s.calls} calls, {s.failures} failed"
                  for s in sorted(self.services.values(), key=lambda s: s.name)]
        lines.append(f"connection graph: {self.graph.published} updates published")
        if self.front is not None:
            lines.append(f"connections: {self.front.connections} "
                         f"({self.front.legacy_connections} asked for {LEGACY}), "
                         f"{self.front.refused} refused for their Origin")
        return lines
