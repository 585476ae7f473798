"""The bridge: one links_and_nodes client, one Zenoh session, and what goes between them.

`Bridge.start()` connects to the manager (its instance gives the default prefix `ln/<instance>`),
opens the session, serves the mds, declares the bridge's liveliness token and the inbound
subscriptions; `poll()` (every `poll` seconds) takes the manager's topic and service lists and
bridges what the outbound rules select; `tick()` (often) handles liveliness events: remote
bridges coming and going (logged), remote bridges offering batches (their `P/@live/batch`
token: inbound rules take those instead of per-topic samples) and remote services to provide
here.  Topics this bridge
publishes (inbound) and services it provides are never sent back out.
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable
from functools import partial
from typing import Any

from .config import BridgeConfig, ServiceRule, TopicRule
from .inbound import InRule
from .mds import LayoutMismatch, MdResolver, MdServer, MdUnavailable
from .outbound import OutTopic
from .ros2 import node_name, node_token
from .services import GROUP, POOL_THREADS, InService, OutService
from .session import open_session
from .stats import Stats
from .wire import bad_name, live_key

RETRY = 5.0  # seconds before a topic or service that failed to be bridged is tried again


class Bridge:
    def __init__(self, config: BridgeConfig, address: str, say: Callable[[str], None],
                 stop: threading.Event) -> None:
        self.config = config
        self.address = address
        self.say = say
        self.stop = stop
        self.stats = Stats()
        self.prefix = config.prefix or ""
        self.session: Any = None
        self.core: Any = None  # native.Core: the session topic samples go through, or None
        self.batching = False  # outbound samples also go in batches to bridges taking them
        self.client: Any = None
        self.manager: Any = None
        self.md_server: Any = None
        self.mds: Any = None
        self.ros2_node = ""
        self.out_topics: dict[str, OutTopic] = {}
        self.out_services: dict[str, OutService] = {}
        self.in_rules: list[InRule] = []
        self.in_services: dict[str, InService] = {}
        self.inbound_names: set[str] = set()  # topics this bridge publishes here
        self._failed: dict[str, float] = {}  # "kind:name" -> when it may be tried again
        self._reasons: dict[str, str] = {}  # "kind:name" -> why it failed last
        self._events: queue.SimpleQueue[tuple[str, str]] = queue.SimpleQueue()
        self._closers: list[Any] = []
        self._listing_error: str | None = None
        self._pool = False

    # ---- start and stop --------------------------------------------------------------------------
    def start(self) -> bool:
        """Connect everything; False if stopped before the session opened."""
        import links_and_nodes as ln
        from links_and_nodes.tools.scripting import connect

        native = self._wants_core()
        self.manager = connect(self.address)
        instance = self.manager.instance
        if not self.prefix:
            self.prefix = f"ln/{instance}"
            if why := bad_name(self.prefix):
                raise ValueError(f"default prefix {self.prefix!r} does not work ({why}): "
                                 "give --prefix")
        self.client = ln.client(self.config.name, self.address)
        opened = open_session(self.config, self.say, self.stop, native)
        if opened is None:
            return False
        self.session, self.core = opened
        # batches come from the core only: with --ros2 outbound topics go through Python
        self.batching = self.core is not None and self.config.batch and not self.config.ros2
        self.mds = MdResolver(self.session)
        self.md_server = MdServer(self.session, self.prefix)
        liveliness = self.session.liveliness()
        self._closers.append(liveliness.declare_subscriber(
            "**/@live/bridge", self._on_bridge_token, history=True))
        remotes = {r.remote for r in self.config.services if r.direction == "in"}
        for remote in sorted(r for r in remotes if r):
            self._closers.append(liveliness.declare_subscriber(
                live_key(remote, "service", "**"), self._on_service_token, history=True))
        if self.config.ros2:
            self.ros2_node = node_name(instance)
            self._closers.append(liveliness.declare_token(
                node_token(self.config.ros2_domain, str(self.session.zid()), self.ros2_node)))
        for rule in self.config.topics:
            if rule.direction == "in":
                self.in_rules.append(InRule(self, rule))
        if self.core is not None and self.config.batch:
            for remote in sorted({r.remote for r in self.in_rules if r.remote}):
                self._closers.append(liveliness.declare_subscriber(
                    live_key(remote, "batch"), self._on_batch_token, history=True))
        if self.batching:
            self._closers.append(liveliness.declare_token(live_key(self.prefix, "batch")))
        # Declared last: a remote bridge that sees it sees the subscriptions above too.
        self._closers.append(liveliness.declare_token(live_key(self.prefix, "bridge")))
        endpoints = ", ".join([f"listening on {e}" for e in self.config.listen]
                              + [f"connecting to {e}" for e in self.config.connect])
        zid = self.core.zid() if self.core is not None else self.session.zid()
        path = "the native core" if self.core is not None else "Python"
        self.say(f"bridge {self.prefix} up: instance '{instance}', Zenoh {self.config.mode} "
                 f"{zid}{', ' + endpoints if endpoints else ''}; topic samples through {path}")
        return True

    def _wants_core(self) -> bool:
        """Whether topic samples go through the native core (native.py): `native` on needs
        it, auto takes it if it loads and says so if not."""
        if self.config.native == "off":
            return False
        from .native import CoreUnavailable, load_core

        try:
            load_core()
        except CoreUnavailable as exc:
            if self.config.native == "on":
                raise RuntimeError(f"native on, but the native core cannot be loaded: {exc}; "
                                   "build it with `scons` (needs cargo)") from None
            if exc.refused:
                self.say(f"the native core does not match this bridge: {exc}; topic samples "
                         "go through Python (slower)")
            else:
                self.say("the native core is not built: topic samples go through Python "
                         "(slower; `scons` builds it when cargo is installed)")
            return False
        return True

    def close(self) -> None:
        for group in (self.out_topics, self.out_services, self.in_services):
            for thing in list(group.values()):
                try:
                    thing.close()
                except Exception as exc:  # noqa: BLE001 - keep closing the rest
                    self.say(f"closing {thing.name}: {exc}")
            group.clear()
        for rule in self.in_rules:
            rule.close()
        for thing in reversed(self._closers):
            try:
                thing.undeclare()
            except Exception:  # noqa: BLE001
                pass
        if self.md_server is not None:
            self.md_server.close()
        if self.session is not None:
            self.session.close()
        if self.core is not None:
            self.core.close()
        if self.client is not None:
            self.client.close()
        if self.manager is not None:
            self.manager.close()

    # ---- liveliness --------------------------------------------------------------------------------
    def _on_bridge_token(self, sample: Any) -> None:
        key = str(sample.key_expr)
        prefix = key.removesuffix("/@live/bridge")
        if prefix != self.prefix:
            self._events.put(("bridge_" + str(sample.kind).rsplit(".", 1)[-1].lower(), prefix))

    def _on_batch_token(self, sample: Any) -> None:
        prefix = str(sample.key_expr).removesuffix("/@live/batch")
        on = str(sample.kind).endswith("PUT")
        self._events.put(("batch_on" if on else "batch_off", prefix))

    def _on_service_token(self, sample: Any) -> None:
        key = str(sample.key_expr)
        prefix, _, name = key.partition("/@live/service/")
        if str(sample.kind).endswith("PUT"):
            self._events.put(("service", f"{prefix}\0{name}"))
        else:
            self._events.put(("service_gone", f"{prefix}\0{name}"))

    def tick(self) -> None:
        while True:
            try:
                kind, what = self._events.get_nowait()
            except queue.Empty:
                return
            if kind == "bridge_put":
                self.say(f"remote bridge {what} is up")
            elif kind == "bridge_delete":
                self.say(f"remote bridge {what} is gone (its samples and services stop "
                         "until it is back)")
            elif kind in ("batch_on", "batch_off"):
                self._take_batches(what, kind == "batch_on")
            elif kind == "service":
                self._provide(*what.split("\0"))
            elif kind == "service_gone":
                prefix, name = what.split("\0")
                if name in self.in_services:
                    self.say(f"service '{name}': {prefix} no longer serves it; calls fail "
                             "until it is back")

    def _take_batches(self, remote: str, on: bool) -> None:
        """The inbound rules of `remote` take its batches (it offers them) or its per-topic
        samples again (it stopped: gone, or restarted without); the core says `topics from
        <remote>: samples come in batches` (or `one by one`) once the switch is done."""
        for rule in self.in_rules:
            if rule.remote == remote:
                rule.set_batch(on)

    def _provide(self, remote: str, name: str) -> None:
        rule = self.config.service_rule(name, "in")
        if rule is None or rule.remote != remote or name in self.in_services:
            return
        try:
            self.in_services[name] = InService(self, name, rule)
        except (LayoutMismatch, MdUnavailable) as exc:
            self.say(f"error: {exc}")
            return
        except Exception as exc:  # noqa: BLE001 - LnError (a provider of that name exists)
            self.say(f"service '{name}' from {remote} cannot be provided here: {exc}")
            return
        self.say(f"service '{name}': provided here, calls go to {remote}")

    def use_service_pool(self) -> None:
        if not self._pool:
            self.client.set_max_threads(GROUP, POOL_THREADS)
            self.client.handle_service_group_in_thread_pool(GROUP, GROUP)
            self._pool = True

    def on_inbound_published(self, name: str) -> None:
        self.inbound_names.add(name)

    # ---- outbound discovery ------------------------------------------------------------------------
    def poll(self) -> None:
        """Bridge the topics and services of the manager's lists that outbound rules select."""
        wants_topics = any(r.direction == "out" for r in self.config.topics)
        wants_services = any(r.direction == "out" for r in self.config.services)
        if not (wants_topics or wants_services):
            return
        listed = self._list(wants_topics, wants_services)
        if listed is None:
            return
        topics, services = listed
        now = time.monotonic()
        for entry in topics:
            name, md_name = str(entry.get("name", "")), str(entry.get("md_name", ""))
            if name in self.out_topics or name in self.inbound_names or not md_name:
                continue
            rule = self.config.topic_rule(name, "out")
            if rule is not None and self._may_try("topic", name, now):
                self._bridge_out("topic", name, now,
                                 partial(self._out_topic, name, md_name, rule))
        for entry in services:
            name, md_name = str(entry.get("name", "")), str(entry.get("md_name", ""))
            if name in self.out_services or name in self.in_services or not md_name:
                continue
            srule = self.config.service_rule(name, "out")
            if srule is not None and self._may_try("service", name, now):
                self._bridge_out("service", name, now,
                                 partial(self._out_service, name, md_name, srule))

    def _list(self, topics: bool, services: bool) -> tuple[list[Any], list[Any]] | None:
        """The manager's topic and service lists (empty where not wanted); None, said once per
        distinct error, when the manager cannot be asked (the next poll retries)."""
        from links_and_nodes.tools.scripting import connect

        try:
            if self.manager is None:
                self.manager = connect(self.address)
            listed = (self.manager.topics() if topics else [],
                      self.manager.services() if services else [])
        except Exception as exc:  # noqa: BLE001 - ManagerError, lost connection: retry
            if self.manager is not None:
                self.manager.close()
                self.manager = None
            if str(exc) != self._listing_error:
                self._listing_error = str(exc)
                self.say(f"cannot list the manager's topics and services (will retry): {exc}")
            return None
        self._listing_error = None
        return listed

    def _may_try(self, kind: str, name: str, now: float) -> bool:
        """Whether `name` may be bridged now: not in its back-off after a failure, and a name
        that can be part of a key expression (else it is given up, said once)."""
        if self._failed.get(f"{kind}:{name}", 0.0) > now:
            return False
        if why := bad_name(name):
            self._give_up(kind, name, f"its name cannot be a key expression: {why}", now)
            return False
        return True

    def _bridge_out(self, kind: str, name: str, now: float, make: Callable[[], str]) -> None:
        """Run `make` (which bridges `name` and returns the line saying so); a failure gives
        the name up for a while."""
        try:
            said = make()
        except Exception as exc:  # noqa: BLE001 - LnError, MdError, dynamic fields
            self._give_up(kind, name, str(exc), now)
            return
        self.say(said)

    def _out_topic(self, name: str, md_name: str, rule: TopicRule) -> str:
        self.out_topics[name] = OutTopic(self, name, md_name, rule)
        return (f"topic '{name}' ({md_name}, {'queued' if rule.queued else 'latest'}): "
                f"bridged out to {self.out_topics[name].key}")

    def _out_service(self, name: str, md_name: str, rule: ServiceRule) -> str:
        self.out_services[name] = OutService(self, name, md_name, rule)
        return f"service '{name}' ({md_name}): served as {self.prefix}/service/{name}"

    def _give_up(self, kind: str, name: str, why: str, now: float) -> None:
        key = f"{kind}:{name}"
        self._failed[key] = now + RETRY
        if self._reasons.get(key) != why:  # said once per reason, not every retry
            self._reasons[key] = why
            self.say(f"{kind} '{name}' is not bridged (tried again every {RETRY:g} s): {why}")
