"""The checks that need the whole configuration, and the final model.

Runs after every file is read: required keys, priority against policy, the names in
depends_on/start_before/start_on_ready and group members (looked up relative to the name
prefixes where they were written), dependency cycles, group recursion, and the hosts and
interfaces that networks name.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Iterable, Mapping

from .argv import CommandSplitError, split_command
from .drafts import Drafts, GroupDraft, MemberRef, NetworkDraft, ProcessDraft, Ref
from .errors import Problem, did_you_mean
from .model import Config, Instance, Interface, Location, OutputLog, Policy, Process

_GLOB_CHARS = "*?["


def build(drafts: Drafts, defines: Mapping[str, str], manager: str | None,
          main: str) -> tuple[Config | None, list[Problem]]:
    """The model, or None and the problems found."""
    r = _Resolver(drafts)
    instance = r.instance(manager, main)
    for d in drafts.processes.values():
        r.process(d)
    for s in drafts.states.values():
        if not s.has_check and "check" not in s.failed:
            r.problem(s.state.location, f"state '{s.state.name}' has no 'check'")
    r.references()
    r.cycles()
    r.groups()
    for n in drafts.networks.values():
        r.network(n)
    if r.problems or instance is None:
        return None, r.problems
    config = Config(
        files=list(drafts.files),
        instance=instance,
        defines=dict(defines),
        hosts=drafts.hosts,
        node_map=drafts.node_map,
        networks={name: d.network for name, d in drafts.networks.items()},
        topic_settings=list(drafts.topic_settings),
        loggers=dict(drafts.loggers),
        access_rules=list(drafts.access_rules),
        processes={name: d.process for name, d in drafts.processes.items()},
        states={name: d.state for name, d in drafts.states.items()},
        groups={name: d.group for name, d in drafts.groups.items()},
        message_definition_dirs=drafts.message_definition_dirs,
    )
    return config, []


class _Resolver:
    def __init__(self, drafts: Drafts) -> None:
        self.d = drafts
        self.problems: list[Problem] = []

    def problem(self, loc: Location, message: str) -> None:
        self.problems.append(Problem(loc, message))

    def instance(self, manager: str | None, main: str) -> Instance | None:
        draft = self.d.instance
        if draft is None:
            self.problem(Location(main, 1, 1), "no 'instance' section (it sets 'name' and "
                                               "'manager')")
            return None
        if draft.name is None and "name" not in draft.failed:
            self.problem(draft.loc, "the instance section has no 'name'")
        address = manager or draft.manager
        if address is None and "manager" not in draft.failed:
            self.problem(draft.loc, "the instance section has no 'manager' (HOST:PORT or "
                                    ":PORT)")
        if draft.name is None or address is None:
            return None
        return Instance(draft.name, address, draft.loc, draft.documentation,
                        draft.webui_auth_file, draft.webui, draft.webui_port,
                        draft.security, draft.client_key_file, draft.client_uids,
                        draft.client_gids, draft.webui_tls_cert, draft.webui_tls_key)

    # ------------------------------------------------------------------ processes

    def process(self, d: ProcessDraft) -> None:
        p = d.process
        if not d.has_command and "command" not in d.failed:
            self.problem(p.location, f"process '{p.name}' has no 'command'")
        elif d.command_value is not None and "start_in_shell" not in p.flags:
            try:
                p.argv = split_command(p.command)
            except CommandSplitError as exc:
                self.problem(d.command_value.at(exc.offset), f"process '{p.name}': {exc}")
        if d.log_path is not None:
            log = OutputLog(d.log_path)
            if d.log_size is not None:
                log.size_limit = d.log_size
            if d.log_keep is not None:
                log.keep_count = d.log_keep
            p.output_log = log
        p.key_locations = {key: loc for key, (loc, _) in d.key_locs.items()}
        if {"policy", "priority"} & d.failed:
            return
        if p.policy is Policy.OTHER:
            lo, hi, why = -20, 19, "for SCHED_OTHER (a nice value)"
        else:
            lo, hi, why = 1, 99, f"for {p.policy.value}"
        if lo <= p.priority <= hi:
            return
        if "priority" in d.key_locs:
            loc, note = d.key_locs["priority"]
            self.problem(loc, f"'priority' must be between {lo} and {hi} {why}, "
                              f"got {p.priority}{note}")
        else:
            loc, note = d.key_locs["policy"]
            self.problem(loc, f"{p.policy.value} needs a 'priority' between {lo} and {hi}"
                              f"{note}")

    def references(self) -> None:
        procs, states = self.d.processes, self.d.states
        for d in procs.values():
            p = d.process
            for key in ("depends_on", "start_before", "start_on_ready"):
                targets: list[str] = []
                for ref in d.refs[key]:
                    found = find(ref, procs) or (find(ref, states) if key == "depends_on"
                                                 else None)
                    if found is None:
                        self._unknown_ref(ref, key, p)
                    elif found not in targets:
                        targets.append(found)
                setattr(p, key, targets)

    def _unknown_ref(self, ref: Ref, key: str, p: Process) -> None:
        what = "process or state" if key == "depends_on" else "process"
        where = f"in '{key}' of process '{p.name}'"
        other = find(ref, self.d.groups) or (find(ref, self.d.states)
                                              if key != "depends_on" else None)
        if other is not None:
            kind = "group" if other in self.d.groups else "state"
            self.problem(ref.loc, f"'{ref.text}' {where} is a {kind}, not a {what}{ref.note}")
            return
        names = list(self.d.processes) + (list(self.d.states) if key == "depends_on" else [])
        hint = did_you_mean(ref.text, relative_names(names, ref.scopes))
        self.problem(ref.loc, f"unknown {what} '{ref.text}' {where}{hint}{ref.note}")

    def cycles(self) -> None:
        edges: dict[str, list[tuple[str, Ref]]] = {}
        for name, d in self.d.processes.items():
            out = edges.setdefault(name, [])
            for key in ("depends_on", "start_before"):
                for ref in d.refs[key]:
                    target = find(ref, self.d.processes)
                    if target is not None:
                        out.append((target, ref))
        for path, ref in find_cycles(list(self.d.processes), edges):
            self.problem(ref.loc, f"dependency cycle: {' -> '.join(path)}{ref.note}")

    # ------------------------------------------------------------------ groups

    def groups(self) -> None:
        edges: dict[str, list[tuple[str, Ref]]] = {}
        for name, g in self.d.groups.items():
            edges[name] = self._members(g)
        for path, ref in find_cycles(list(self.d.groups), edges):
            self.problem(ref.loc, f"group recursion: {' -> '.join(path)}{ref.note}")

    def _members(self, g: GroupDraft) -> list[tuple[str, Ref]]:
        """Resolve the members of `g`; returns its edges to member groups."""
        name = g.group.name
        allow_empty = "allow_empty" in g.group.flags
        members: list[str] = []
        excluded: set[str] = set()
        nested: list[tuple[str, Ref]] = []
        before = len(self.problems)
        for ref in g.members:
            hits = self._match(ref)
            if ref.exclude:
                excluded.update(hits)
                continue
            if not hits and not allow_empty:
                if any(c in ref.text for c in _GLOB_CHARS):
                    self.problem(ref.loc, f"pattern '{ref.text}' in group '{name}' matches no "
                                          f"process or state (flag 'allow_empty' allows "
                                          f"that){ref.note}")
                else:
                    names = [*self.d.processes, *self.d.states, *self.d.groups]
                    hint = did_you_mean(ref.text, relative_names(names, ref.scopes))
                    self.problem(ref.loc, f"unknown member '{ref.text}' in group '{name}'"
                                          f"{hint}{ref.note}")
            for hit in hits:
                if hit in self.d.groups:
                    nested.append((hit, ref))
                if hit not in members:
                    members.append(hit)
        g.group.members = [m for m in members if m not in excluded]
        if not g.group.members and not allow_empty and len(self.problems) == before:
            self.problem(g.group.location, f"group '{name}' has no members (flag "
                                           "'allow_empty' allows that)")
        return nested

    def _match(self, ref: Ref) -> list[str]:
        if not any(c in ref.text for c in _GLOB_CHARS):
            for table in (self.d.processes, self.d.states, self.d.groups):
                found = find(ref, table)
                if found is not None:
                    return [found]
            return []
        for scope in ref.scopes:
            pattern = f"{scope}/{ref.text}" if scope else ref.text
            hits = [n for n in self.d.order if fnmatch.fnmatchcase(n, pattern)]
            if hits:
                return hits
        return []


    # ------------------------------------------------------------------ networks

    def network(self, d: NetworkDraft) -> None:
        net = d.network
        where = f"network '{net.name}'"
        before = len(self.problems)
        for ref in d.items:
            if ref.member.subnet is None:
                self._check_interface(ref, where)
            (net.excluded if ref.exclude else net.members).append(ref.member)
        members_ok = len(self.problems) == before
        hosts = self.d.hosts
        for g in d.gateways:
            if g.name not in hosts:
                self.problem(g.loc, f"unknown host '{g.name}' in 'preferred_gateways' of "
                                    f"{where}{did_you_mean(g.name, hosts)}{g.note}")
            elif g.name not in net.preferred_gateways:
                net.preferred_gateways.append(g.name)
        net.interfaces = [
            i for i in (Interface(h.name, label, address) for h in hosts.values()
                        for label, address in h.interfaces.items())
            if any(m.matches(i) for m in net.members)
            and not any(m.matches(i) for m in net.excluded)]
        if "member_interfaces" in d.failed or not members_ok or net.interfaces:
            return
        if d.items_loc is None:
            self.problem(net.location, f"{where} has no 'member_interfaces'")
        else:
            self.problem(d.items_loc, f"{where} has no member interfaces (no interface in "
                                      "'hosts' matches 'member_interfaces' without being "
                                      f"excluded){d.items_note}")

    def _check_interface(self, ref: MemberRef, where: str) -> None:
        m = ref.member
        assert m.host is not None and m.interface is not None
        host = self.d.hosts.get(m.host)
        if host is None:
            self.problem(m.location, f"unknown host '{m.host}' in 'member_interfaces' of "
                                     f"{where}{did_you_mean(m.host, self.d.hosts)}{ref.note}")
        elif m.interface not in host.interfaces:
            hint = (did_you_mean(m.interface, host.interfaces) if host.interfaces
                    else f" (host '{m.host}' has no interfaces in 'hosts')")
            self.problem(ref.detail_loc, f"unknown interface '{m.interface}' of host "
                                         f"'{m.host}' in 'member_interfaces' of {where}"
                                         f"{hint}{ref.note}")


def find(ref: Ref, table: Mapping[str, object]) -> str | None:
    """The full name `ref` means in `table`, trying the innermost name prefix first."""
    for scope in ref.scopes:
        full = f"{scope}/{ref.text}" if scope else ref.text
        if full in table:
            return full
    return None


def relative_names(names: Iterable[str], scopes: tuple[str, ...]) -> list[str]:
    """Names as written under the given prefixes, for "did you mean"."""
    out = list(names)
    for scope in scopes:
        if scope:
            out += [n[len(scope) + 1:] for n in names if n.startswith(scope + "/")]
    return out


def find_cycles(nodes: list[str], edges: dict[str, list[tuple[str, Ref]]]
                ) -> list[tuple[list[str], Ref]]:
    """One cycle per strongly connected component that has one: the shortest cycle through
    the component's first node (in `nodes` order), with the reference of its first edge."""
    order = {n: i for i, n in enumerate(nodes)}
    out = []
    for component in _components(nodes, edges):
        start = min(component, key=order.__getitem__)
        inside = set(component)
        if len(component) == 1 and not any(t == start for t, _ in edges.get(start, [])):
            continue
        # Breadth-first from start back to start, staying inside the component.
        parent: dict[str, tuple[str, Ref]] = {}
        queue = [start]
        found: tuple[str, Ref] | None = None
        while queue and found is None:
            nxt = []
            for node in queue:
                for target, ref in edges.get(node, []):
                    if target == start:
                        found = (node, ref)
                        break
                    if target in inside and target not in parent:
                        parent[target] = (node, ref)
                        nxt.append(target)
                if found is not None:
                    break
            queue = nxt
        assert found is not None
        path = [start]
        node, ref = found
        while node != start:
            path.append(node)
            node, ref = parent[node]
        path.append(start)
        path.reverse()
        out.append((path, ref))
    return out


def _components(nodes: list[str], edges: dict[str, list[tuple[str, Ref]]]) -> list[list[str]]:
    """Strongly connected components (Tarjan's algorithm, without recursion)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    result = []
    for root in nodes:
        if root in index:
            continue
        work = [(root, 0)]
        while work:
            node, i = work.pop()
            if i == 0:
                index[node] = low[node] = len(index)
                stack.append(node)
                on_stack.add(node)
            targets = [t for t, _ in edges.get(node, [])]
            if i < len(targets):
                work.append((node, i + 1))
                t = targets[i]
                if t not in index:
                    work.append((t, 0))
                elif t in on_stack:
                    low[node] = min(low[node], index[t])
                continue
            if low[node] == index[node]:
                component = []
                while True:
                    top = stack.pop()
                    on_stack.discard(top)
                    component.append(top)
                    if top == node:
                        break
                result.append(component)
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
    return result
