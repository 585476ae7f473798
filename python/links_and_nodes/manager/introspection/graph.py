"""`graph` in the command table (docs/introspection.md, "graph"; the web UI's graph page):
the running system as nodes and edges, from what the manager knows.

Nodes: the configuration's processes (with host, `.lnc` groups, state) and every client
the manager did not start, merged into its process when it is one (by pid, else by name);
topics, services, pull topics, and the `state` sections processes depend on.  Edges:
publisher -> topic -> subscriber, caller -> service -> provider (callers: the clients that
looked the service up, FIND_SERVICE), topic -> pull topic, and the `.lnc` dependencies
(`depends_on`, a second layer).  Rates come from counters that exist: a topic's published
samples (its ring's write_seq), a service's calls as its provider reports them, the
forwarding streams' own rates between hosts; they are taken between two looks
(graph_rates.py), so the first look of a manager waits `window` seconds for a second one."""

from __future__ import annotations

import re
import time
import weakref
from typing import TYPE_CHECKING, Any, Protocol

from ...tools.commands import Arg, Command, register
from . import graph_views as views
from .graph_rates import Rates

if TYPE_CHECKING:
    from ..registry.model import Client

# the bridges and recorders, which are ordinary clients: found by a word of their client
# name or of their process's command
BRIDGES = {"foxglove": ("ln_foxglove", "foxglove_bridge"),
           "zenoh": ("ln_zenoh", "zenoh_bridge"),
           "record": ("ln_record", "record_cli"),
           "play": ("ln_play", "play_cli")}
# the manager's own clients and those of `ln_manager topic ...`, the console, scripts
TOOLS = ("ln_manager", "ln_console", "ln_script", "ln_topic_", "ln_service_call")
_SUFFIX = re.compile(r"-\d+$")  # the registry's `name-2` for a taken name


class Control(Protocol):
    """What the graph uses of the manager's Control (frontends/control.py)."""

    core: Any
    scheduler: Any  # the Scheduler of a configuration, or None
    network_view: Any  # the hosts of a multi-host configuration, or None
    pull: Any  # the pull topics, or None


_rates: weakref.WeakKeyDictionary[Any, Rates] = weakref.WeakKeyDictionary()


def bridge_of(*words: str) -> str:
    """"foxglove", "zenoh", "record", "play", "tool" or "" for a client name or command."""
    text = " ".join(words)
    for kind, marks in BRIDGES.items():
        if any(m in text for m in marks):
            return kind
    return "tool" if any(w.startswith(TOOLS) for w in words) else ""


async def counters(control: Control) -> dict[str, int]:
    """The counters rates are made of: "t:TOPIC" published samples, "s:SERVICE" calls."""
    core = control.core
    out = {f"t:{name}": int(await core.topic_published(name))
           for name in list(core.registry.topics)}
    for service in core.service_registry.sorted():
        out[f"s:{service.name}"] = int(service.calls)
    return out


async def graph(control: Control, args: dict[str, Any]) -> dict[str, Any]:
    """The answer of `graph`: {nodes, edges, hosts, groups, streams, rate_span_s}."""
    import asyncio  # here: the command line that only registers the command never loads it

    rates = _rates.setdefault(control, Rates())
    now = time.monotonic()
    counted = await counters(control)
    if rates.base(now) is None and args["window"] > 0:
        rates.add(now, counted)
        await asyncio.sleep(args["window"])
        counted = await counters(control)
        now = time.monotonic()
    per_s, span = rates.add(now, counted)
    return Builder(control, counted, per_s).build(span)


class Builder:
    """One graph from the manager's registry, scheduler and network view."""

    def __init__(self, control: Control, counted: dict[str, int],
                 per_s: dict[str, float]) -> None:
        self.control = control
        self.counted = counted
        self.per_s = per_s
        self.nodes: dict[str, dict[str, Any]] = {}
        self.edges: dict[tuple[str, str, str], dict[str, Any]] = {}
        self.client_node: dict[int, str] = {}  # client id -> node id
        self.client_host: dict[int, str] = {}

    def build(self, span: float | None) -> dict[str, Any]:
        groups = self._processes()
        self._clients()
        streams = self._topics()
        self._services()
        self._pull()
        hosts = sorted({n["host"] for n in self.nodes.values() if n.get("host")})
        return {"nodes": list(self.nodes.values()), "edges": list(self.edges.values()),
                "hosts": hosts, "groups": groups, "streams": streams,
                "rate_span_s": round(span, 3) if span is not None else None}

    # ---- processes and clients -------------------------------------------------------------
    def _processes(self) -> list[dict[str, Any]]:
        sched = self.control.scheduler
        if sched is None:
            return []
        config = sched.config
        member_of: dict[str, list[str]] = {}
        groups = []
        for name, group in config.groups.items():
            members = [m for m in group.members if m in sched.procs]
            groups.append({"name": name, "members": members})
            for m in members:
                member_of.setdefault(m, []).append(name)
        states = getattr(sched, "states", {}) or {}
        for name, proc in sched.procs.items():
            cfg = proc.cfg
            self.nodes[f"p:{name}"] = {
                "id": f"p:{name}", "kind": "process", "name": name, "host": cfg.node,
                "group": (member_of.get(name) or [""])[0], "groups": member_of.get(name, []),
                "state": proc.state.value, "pid": proc.pid, "clients": [],
                "bridge": bridge_of(cfg.command)}
        for name, proc in sched.procs.items():
            for dep in proc.cfg.depends_on:
                if dep in sched.procs:
                    self._edge(f"p:{name}", f"p:{dep}", "depends_on")
                elif dep in states:
                    node = f"st:{dep}"
                    self.nodes.setdefault(node, {"id": node, "kind": "state", "name": dep,
                                                 "up": states[dep].up})
                    self._edge(f"p:{name}", node, "depends_on")
        return groups

    def _process_of(self, client: Client) -> str | None:
        """The process node of a client: the process with its pid on its host, else the one
        whose name it has (LN_PROGRAM_NAME: the process name with "." for "/")."""
        sched = self.control.scheduler
        if sched is None:
            return None
        from ..processes.output_levels import process_finder

        found = process_finder(sched.procs, any_node=self.control.core.hosts is None)(
            self.client_host[client.id], client.pid)
        if found:
            return f"p:{found}"
        base = _SUFFIX.sub("", client.name)
        for name in sched.procs:
            if base in (name, name.replace("/", ".")):
                return f"p:{name}"
        return None

    def _clients(self) -> None:
        hosts = self.control.core.hosts
        for client in sorted(self.control.core.registry.clients.values(), key=lambda c: c.id):
            self.client_host[client.id] = hosts.host_label(client) if hosts is not None \
                else "localhost"
            node = self._process_of(client)
            if node is None:
                node = f"c:{client.name}"
                self.nodes[node] = {"id": node, "kind": "client", "name": client.name,
                                    "host": self.client_host[client.id], "group": "",
                                    "groups": [], "state": "connected", "pid": client.pid,
                                    "clients": [], "bridge": bridge_of(client.name)}
            entry = self.nodes[node]
            entry["clients"].append(client.name)
            if not entry["bridge"]:
                entry["bridge"] = bridge_of(client.name)
            self.client_node[client.id] = node

    # ---- topics, services, pull topics -----------------------------------------------------
    def _rate(self, key: str) -> float | None:
        rate = self.per_s.get(key)
        return round(rate, 2) if rate is not None else None

    def _topics(self) -> list[dict[str, Any]]:
        from ..registry.model import PortKind

        view = self.control.network_view
        streams = view.stream_listing()["streams"] if view is not None else []
        for name, topic in sorted(self.control.core.registry.topics.items()):
            node, rate = f"t:{name}", self._rate(f"t:{name}")
            self.nodes[node] = {
                "id": node, "kind": "topic", "name": name, "md_name": topic.md_name,
                "message_size": topic.message_size, "published": self.counted.get(node, 0),
                "publishers": topic.publishers, "subscribers": topic.subscribers,
                "rate_hz": rate,
                "bytes_per_s": round(rate * topic.message_size) if rate is not None else None}
            ports = sorted(topic.ports.values(), key=lambda p: p.id)
            origin = {self.client_host[p.client.id] for p in ports
                      if p.kind is PortKind.PUBLISHER and p.client.id in self.client_host}
            for port in ports:
                who = self.client_node.get(port.client.id)
                if who is None:  # a client that is going: its node is gone already
                    continue
                if port.kind is PortKind.PUBLISHER:
                    single = topic.publishers == 1
                    self._edge(who, node, "publishes", rate_hz=rate if single else None,
                               bytes_per_s=self.nodes[node]["bytes_per_s"] if single
                               else None)
                    continue
                self._subscriber(node, who, port, origin, [s for s in streams
                                                           if s["topic"] == name])
        return [{k: s[k] for k in ("topic", "src", "dst", "transport", "msgs_per_s",
                                   "bytes_per_s", "drops", "error")} for s in streams]

    def _subscriber(self, node: str, who: str, port: Any, origin: set[str],
                    streams: list[dict[str, Any]]) -> None:
        host = self.client_host[port.client.id]
        topic = self.nodes[node]
        extra: dict[str, Any] = {"mode": "latest" if port.buffers == 1 else "queued"}
        if not origin:
            extra["transport"] = "-"
        elif host in origin:
            extra.update(transport="shm", rate_hz=topic["rate_hz"],
                         bytes_per_s=topic["bytes_per_s"])
        else:
            via = [s for s in streams if s["dst"] == host]
            if via:
                s = via[0]
                extra.update(transport=f"forwarded {s['transport']}",
                             rate_hz=s["msgs_per_s"], bytes_per_s=s["bytes_per_s"],
                             forwarded={"src": s["src"], "dst": s["dst"],
                                        "transport": s["transport"], "drops": s["drops"]})
            else:
                extra["transport"] = "forwarded (no stream)"
        self._edge(node, who, "subscribes", **extra)

    def _services(self) -> None:
        registry = self.control.core.service_registry
        callers = getattr(registry, "callers", {})
        for service in registry.sorted():
            node, rate = f"s:{service.name}", self._rate(f"s:{service.name}")
            self.nodes[node] = {"id": node, "kind": "service", "name": service.name,
                                "md_name": service.offer.md_name, "calls": service.calls,
                                "errors": service.errors, "calls_per_s": rate}
            provider = self.client_node.get(service.provider.id)
            if provider is not None:
                self._edge(node, provider, "provides", calls_per_s=rate)
            for client in sorted(callers.get(service.name, {}).values(), key=lambda c: c.id):
                caller = self.client_node.get(client.id)
                if caller is not None and caller != provider:
                    self._edge(caller, node, "calls")

    def _pull(self) -> None:
        pull = self.control.pull
        for entry in pull.listing() if pull is not None else []:
            node = f"u:{entry['topic']}@{entry['host']}"
            self.nodes[node] = {"id": node, "kind": "pull", "name": entry["name"],
                                "topic": entry["topic"], "host": entry["host"],
                                "port": entry["port"], "error": entry["error"]}
            if f"t:{entry['topic']}" in self.nodes:
                self._edge(f"t:{entry['topic']}", node, "pull")

    def _edge(self, src: str, dst: str, kind: str, **extra: Any) -> None:
        key = (src, dst, kind)
        if key in self.edges:
            self.edges[key]["ports"] += 1
            return
        self.edges[key] = {"from": src, "to": dst, "kind": kind, "ports": 1, **extra}


register(
    Command("graph", "processes, topics and services as nodes and edges, with rates",
            "topics", graph,
            (Arg("window", "float", "seconds between the two looks that give the rates, "
                 "when the manager has no recent look", default=1.0, low=0, high=10,
                 metavar="S", error="--window: {value!r} is not a number of seconds 0..10"),
             Arg("json", "bool", "print the graph as JSON", default=False, where="text"),
             Arg("dot", "bool", "print the graph in graphviz's DOT language", default=False,
                 where="text")),
            result="nodes: [{id, kind, name, ...}], edges: [{from, to, kind, ...}], hosts, "
                   "groups, streams, rate_span_s",
            console_format=views.graph_lines, json_view=views.json_view,
            script_result=lambda result: views.json_view(result),
            script_doc="The running system as a graph (docs/introspection.md, \"graph\"): "
                       "{\"nodes\": [{id, kind (process, client, topic, service, pull, "
                       "state), name, ...}], \"edges\": [{from, to, kind (publishes, "
                       "subscribes, provides, calls, pull, depends_on), rate_hz, "
                       "bytes_per_s, ...}], \"hosts\", \"groups\", \"streams\", "
                       "\"rate_span_s\"}."),
)
