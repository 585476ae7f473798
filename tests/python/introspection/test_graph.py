"""`ln_manager graph` (docs/introspection.md, "graph"): the JSON of a small system (a
publisher, a provider, a peer that subscribes and calls, the command line's own client) has
exactly its nodes and edges, with a rate for the published topic; a client that goes takes
its node and edges along; `--dot` is accepted by graphviz's `dot`.  The pure parts: rates
between looks, the DOT text of awkward names."""

from __future__ import annotations

import json
import shutil
import subprocess
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from buildtree import missing_test_tool

from links_and_nodes.manager.introspection.graph_rates import MIN_SPAN, Rates
from links_and_nodes.manager.introspection.graph_views import dot, tables
from links_and_nodes.tools.scripting import connect

from .conftest import LIMIT, MDS, Lab

NODES = {("c:probe_pub", "client"), ("c:adjuster", "client"), ("c:peer", "client"),
         ("c:ln_script", "client"), ("t:probe.state", "topic"),
         ("s:probe.adjust", "service")}
EDGES = {("c:probe_pub", "t:probe.state", "publishes"),
         ("t:probe.state", "c:peer", "subscribes"),
         ("c:peer", "s:probe.adjust", "calls"),
         ("s:probe.adjust", "c:adjuster", "provides")}


def small_system(lab: Lab) -> None:
    lab.publisher("probe.state")
    lab.provider("probe.adjust")
    lab.spawn("graph_peer.py", "peer", "probe.state", "probe.adjust", str(MDS))


def edges(graph: dict[str, Any]) -> set[tuple[str, str, str]]:
    return {(e["from"], e["to"], e["kind"]) for e in graph["edges"]}


def until(look: Callable[[], dict[str, Any]]) -> dict[str, Any]:
    """The first non-empty answer of look(); AssertionError after LIMIT seconds."""
    deadline = time.monotonic() + LIMIT
    while time.monotonic() < deadline:
        value = look()
        if value:
            return value
        time.sleep(0.1)
    raise AssertionError(f"not within {LIMIT} s")


def test_graph_json_has_exactly_the_nodes_and_edges(lab: Lab) -> None:
    small_system(lab)
    run = lab.ln_manager("graph", "--json")
    assert run.returncode == 0, run.stderr
    graph = json.loads(run.stdout)
    assert {(n["id"], n["kind"]) for n in graph["nodes"]} == NODES
    assert edges(graph) == EDGES
    by_id = {n["id"]: n for n in graph["nodes"]}
    assert by_id["c:ln_script"]["bridge"] == "tool"
    assert by_id["c:peer"]["bridge"] == "" and by_id["c:peer"]["host"] == "localhost"
    topic = by_id["t:probe.state"]
    assert topic["md_name"] == "lntest/probe" and topic["publishers"] == 1
    assert topic["subscribers"] == 1 and topic["published"] > 0
    # the first look of this manager waited --window (1 s) for a second one
    assert graph["rate_span_s"] is not None and topic["rate_hz"] > 0
    assert topic["bytes_per_s"] == round(topic["rate_hz"] * topic["message_size"])
    sub = next(e for e in graph["edges"] if e["kind"] == "subscribes")
    assert sub["mode"] == "queued" and sub["transport"] == "shm"
    assert by_id["s:probe.adjust"]["md_name"] == "lntest/adjust"
    assert graph["hosts"] == ["localhost"] and graph["groups"] == []

    # the scripting API's answer is the same data; a client that goes takes its edges along
    with connect(lab.address, timeout=LIMIT) as mgr:
        assert edges(mgr.graph(window=0)) == EDGES
        peer = lab.procs[-1]
        peer.kill()
        peer.wait()

        def gone() -> dict[str, Any]:
            graph = mgr.graph(window=0)
            return graph if "c:peer" not in {n["id"] for n in graph["nodes"]} else {}

        graph = until(gone)
    assert edges(graph) == {("c:probe_pub", "t:probe.state", "publishes"),
                            ("s:probe.adjust", "c:adjuster", "provides")}


def test_graph_dot_is_read_by_graphviz(lab: Lab, tmp_path: Path) -> None:
    small_system(lab)
    run = lab.ln_manager("graph", "--dot", "--window", "0")
    assert run.returncode == 0, run.stderr
    assert run.stdout.startswith("digraph links_and_nodes {")
    if shutil.which("dot") is None:
        missing_test_tool("graphviz's dot (scripts/setup)")
    svg = subprocess.run(["dot", "-Tsvg"], input=run.stdout, capture_output=True, text=True,
                         timeout=LIMIT)
    assert svg.returncode == 0 and not svg.stderr, svg.stderr
    titles = {line.strip()[len("<title>"):-len("</title>")]
              for line in svg.stdout.splitlines() if line.strip().startswith("<title>")}
    assert {n for n, _ in NODES} <= titles
    assert "t:probe.state&#45;&gt;c:peer" in titles


def test_console_table_names_every_edge(lab: Lab) -> None:
    small_system(lab)
    run = lab.ln_manager("graph")
    assert run.returncode == 0, run.stderr
    lines = run.stdout.splitlines()
    assert any(line.split()[:3] == ["peer", "probe.adjust", "calls"] for line in lines), lines
    assert any(line.split()[:3] == ["probe.state", "peer", "subscribes"] for line in lines)


# ---- pure --------------------------------------------------------------------------------
def test_rates_between_two_looks() -> None:
    rates = Rates()
    assert rates.add(100.0, {"t:a": 10, "s:b": 0}) == ({}, None)
    assert rates.add(100.1, {"t:a": 11}) == ({}, None)  # too close: no base yet
    per_s, span = rates.add(100.0 + 2 * MIN_SPAN, {"t:a": 10 + 100, "s:b": 3, "t:new": 5})
    assert span == 2 * MIN_SPAN
    assert per_s == {"t:a": 100 / span, "s:b": 3 / span}  # a new counter has no rate
    per_s, _ = rates.add(100.0 + 4 * MIN_SPAN, {"t:a": 1})  # went down: made anew
    assert "t:a" not in per_s
    assert rates.add(1000.0, {"t:a": 5}) == ({}, None)  # every look too old


def test_dot_quotes_awkward_names() -> None:
    graph = {"nodes": [{"id": 'c:we"ird\\name', "kind": "client", "name": 'we"ird\\name',
                        "host": "h", "group": "", "state": "connected", "bridge": ""},
                       {"id": "t:x", "kind": "topic", "name": "x", "md_name": "m/x",
                        "rate_hz": 2.0, "bytes_per_s": 20}],
             "edges": [{"from": 'c:we"ird\\name', "to": "t:x", "kind": "publishes",
                        "rate_hz": 2.0, "bytes_per_s": 20}],
             "hosts": ["h"], "groups": [], "streams": [], "rate_span_s": 1.0}
    text = dot(graph)
    assert '"c:we\\"ird\\\\name" -> "t:x" [label="2.0 Hz\\n20 B/s"];' in text
    assert text.count("{") == text.count("}")
    assert any("2.0 Hz" in line for line in tables(graph))
