"""Go to definition and find references in `.lnc` files: templates, defines, include
targets, processes/states/groups named in `depends_on`, `start_before`, `start_on_ready`
and `members`, hosts, and md names (their md file)."""

from __future__ import annotations

from ...config.model import Location
from .names import (
    DEFINE,
    FILE,
    HOST,
    MD,
    NAME,
    TEMPLATE,
    Target,
    all_refs,
    define_uses,
    name_locations,
    resolve_ref,
)
from .reading import Analysis

Site = tuple[Location, int]  # a place and the length of the name there


def definition(analysis: Analysis, target: Target) -> list[Site]:
    parser = analysis.parser
    if target.kind in (FILE, MD):
        return [(Location(target.name, 1, 1), 0)]
    if parser is None:
        return []
    if target.kind == NAME:
        loc = name_locations(analysis).get(target.name)
        return [(loc, len(target.name.rsplit("/", 1)[-1]))] if loc else []
    if target.kind == TEMPLATE:
        template = parser.templates.get(target.name)
        return [(template.loc, len(target.name.rsplit("/", 1)[-1]))] if template else []
    if target.kind == DEFINE:
        sites = [(s.loc, len(s.name)) for s in analysis.records.defines if s.name == target.name]
        return list(dict.fromkeys(sites))
    if target.kind == HOST:
        host = parser.drafts.hosts.get(target.name)
        return [(host.location, len(target.name))] if host else []
    return []


def references(analysis: Analysis, target: Target, include_declaration: bool) -> list[Site]:
    """Every place the target is named, in the files of the read."""
    out = definition(analysis, target) if include_declaration else []
    parser = analysis.parser
    if parser is None:
        return out
    if target.kind == NAME:
        out += [(r.loc, len(r.text)) for r in all_refs(analysis)
                if resolve_ref(analysis, r) == target.name]
    elif target.kind == TEMPLATE:
        out += [(u.loc, len(u.name)) for u in analysis.records.template_uses
                if u.template.name == target.name]
    elif target.kind == DEFINE:
        for file, text in analysis.records.texts.items():
            out += [(loc, length) for _, loc, length in define_uses(text, file, target.name)]
    elif target.kind == HOST:
        for d in parser.drafts.processes.values():
            if d.process.node == target.name and "node" in d.key_locs:
                out.append((d.key_locs["node"][0], len(target.name)))
    return list(dict.fromkeys(out))
