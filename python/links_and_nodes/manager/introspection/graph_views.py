"""The `graph` answer as text: tables for the console and `ln_manager graph`, JSON
(`--json`) and graphviz's DOT language (`--dot`): hosts and `.lnc` groups as clusters,
processes as boxes (bridges filled), topics as ellipses, services as hexagons, pull topics
as notes, edges labelled with their rates, forwarded ones dashed, dependencies dotted.
Pure: only the answer's data."""

from __future__ import annotations

import json
from typing import Any

from ...tools.commands.columns import table

SHAPES = {"process": "box", "client": "box", "topic": "ellipse", "service": "hexagon",
          "pull": "note", "state": "octagon"}
BRIDGE_COLOUR = "#ffe9a8"
STATE_COLOURS = {"ready": "#dff3df", "finished": "#dff3df", "failed": "#f8d0d0",
                 "stopped": "#eeeeee", "connected": "#e8eefc"}


def json_view(result: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in result.items() if k != "ok"}


def rate_text(rate: float | None, unit: str = "Hz") -> str:
    return "" if rate is None else f"{rate:.1f} {unit}"


def bytes_text(n: float | None) -> str:
    if n is None:
        return ""
    for unit in ("B/s", "KB/s", "MB/s"):
        if n < 1000:
            return f"{n:.0f} {unit}" if unit == "B/s" else f"{n:.1f} {unit}"
        n /= 1000
    return f"{n:.1f} GB/s"


def graph_lines(result: dict[str, Any], args: dict[str, Any]) -> list[str]:
    """`--json`, `--dot` or the tables."""
    if args.get("json"):
        return json.dumps(json_view(result), indent=2).splitlines()
    if args.get("dot"):
        return dot(result).splitlines()
    return tables(result)


def _name(nodes: dict[str, dict[str, Any]], node_id: str) -> str:
    node = nodes.get(node_id)
    return node["name"] if node is not None else node_id


def tables(result: dict[str, Any]) -> list[str]:
    nodes = {n["id"]: n for n in result["nodes"]}
    rows = [["node", "kind", "host", "group", "state", "pid", "rate", "bandwidth"]]
    for n in result["nodes"]:
        kind = n["kind"] + (f" ({n['bridge']})" if n.get("bridge") else "")
        if n["kind"] == "service":
            rate, size = rate_text(n.get("calls_per_s"), "calls/s"), ""
        else:
            rate, size = rate_text(n.get("rate_hz")), bytes_text(n.get("bytes_per_s"))
        state = n.get("state", "")
        if n["kind"] == "state":
            state = {True: "up", False: "down"}.get(n.get("up"), "unknown")
        rows.append([n["name"], kind, n.get("host", ""), n.get("group", ""), state,
                     str(n.get("pid") or ""), rate, size])
    lines = table(rows)
    rows = [["from", "to", "edge", "rate", "bandwidth", "via"]]
    for e in result["edges"]:
        rate = e.get("calls_per_s") if e["kind"] == "provides" else e.get("rate_hz")
        rows.append([_name(nodes, e["from"]), _name(nodes, e["to"]),
                     e["kind"].replace("_", " "),
                     rate_text(rate, "calls/s" if e["kind"] == "provides" else "Hz"),
                     bytes_text(e.get("bytes_per_s")),
                     " ".join(filter(None, (e.get("mode", ""), e.get("transport", ""))))])
    lines += [""] + table(rows)
    if result.get("rate_span_s") is None:
        lines.append("(no rates: the manager had no earlier look to compare with)")
    return lines


# ---- DOT ---------------------------------------------------------------------------------
def quote(text: str) -> str:
    """A DOT string literal."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def _label(n: dict[str, Any]) -> str:
    parts = [n["name"]]
    if n["kind"] in ("process", "client"):
        if n.get("bridge"):
            parts.append(f"[{n['bridge']}]")
        parts.append(n.get("state", ""))
    elif n["kind"] == "topic":
        parts += [n.get("md_name", ""), rate_text(n.get("rate_hz"))]
    elif n["kind"] == "service":
        parts += [n.get("md_name", ""), rate_text(n.get("calls_per_s"), "calls/s")]
    elif n["kind"] == "pull":
        parts.append(f"pull on {n.get('host', '')}")
    return "\n".join(p for p in parts if p)


def _node(n: dict[str, Any]) -> str:
    attrs = {"label": _label(n), "shape": SHAPES.get(n["kind"], "box")}
    colour = BRIDGE_COLOUR if n.get("bridge") and n["bridge"] != "tool" else \
        STATE_COLOURS.get(n.get("state", ""))
    if colour:
        attrs.update(style="filled", fillcolor=colour)
    if n["kind"] == "client":
        attrs["style"] = "dashed" + (",filled" if colour else "")
    return f"{quote(n['id'])} [{', '.join(f'{k}={quote(v)}' for k, v in attrs.items())}];"


def _edge(e: dict[str, Any]) -> str:
    attrs: dict[str, str] = {}
    if e["kind"] == "depends_on":
        attrs.update(style="dotted", color="gray50", constraint="false", label="depends on")
    else:
        rate = e.get("calls_per_s") if e["kind"] == "provides" else e.get("rate_hz")
        text = [rate_text(rate, "calls/s" if e["kind"] == "provides" else "Hz"),
                bytes_text(e.get("bytes_per_s"))]
        if e.get("forwarded"):
            f = e["forwarded"]
            attrs["style"] = "dashed"
            text.append(f"{f['transport']} {f['src']} -> {f['dst']}")
        if e["kind"] == "calls":
            attrs["style"] = "dashed"
            text.append("calls")
        label = "\n".join(t for t in text if t)
        if label:
            attrs["label"] = label
    body = ", ".join(f"{k}={quote(v)}" for k, v in attrs.items())
    return f"{quote(e['from'])} -> {quote(e['to'])}" + (f" [{body}]" if body else "") + ";"


def dot(result: dict[str, Any]) -> str:
    """The graph in DOT: a cluster per host, within it one per `.lnc` group."""
    out = ["digraph links_and_nodes {",
           '  graph [rankdir="LR", fontname="sans-serif", fontsize="10"];',
           '  node [fontname="sans-serif", fontsize="10"];',
           '  edge [fontname="sans-serif", fontsize="9"];']
    placed: dict[str, dict[str, list[dict[str, Any]]]] = {}
    loose = []
    for n in result["nodes"]:
        if n.get("host") and n["kind"] in ("process", "client", "pull"):
            placed.setdefault(n["host"], {}).setdefault(n.get("group", ""), []).append(n)
        else:
            loose.append(n)
    for h, (host, groups) in enumerate(sorted(placed.items())):
        out += [f"  subgraph {quote(f'cluster_h{h}')} {{", f"    label={quote('host ' + host)};",
                '    style="rounded"; color="gray60";']
        for g, (group, members) in enumerate(sorted(groups.items())):
            indent = "    "
            if group:
                out += [f"    subgraph {quote(f'cluster_h{h}_g{g}')} {{",
                        f"      label={quote('group ' + group)};", '      color="gray80";']
                indent = "      "
            out += [indent + _node(n) for n in members]
            if group:
                out.append("    }")
        out.append("  }")
    out += ["  " + _node(n) for n in loose]
    out += ["  " + _edge(e) for e in result["edges"]]
    out.append("}")
    return "\n".join(out) + "\n"
