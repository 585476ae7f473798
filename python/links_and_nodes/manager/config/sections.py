"""The section types of a `.lnc` file and the keys each accepts (process keys live in
process_keys.py).  A section object receives the key lines written under its header."""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

from .drafts import GroupDraft, InstanceDraft, KeyLine, ProcessDraft, StateDraft
from .errors import LineError, Problem, closest, did_you_mean
from .expand import BUILTINS, Evaluator
from .model import Host
from .process_keys import process_key, ref_items
from .templates import Template
from .text import Value, split_value, unquote
from .values import fail, parse_address, parse_duration, parse_float, parse_int, parse_ipv4

if TYPE_CHECKING:
    from .parser import Parser

DEFINE_NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_.\-/]*\Z")
HOST_NAME_RE = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.\-]*\Z")
GROUP_FLAGS = frozenset({"allow_empty", "show_opened", "show_closed", "sorted", "unsorted"})


class Section:
    kind = ""
    general_keys = False  # keys are any text up to the colon, expanded (defines, hosts, ...)

    def key(self, p: Parser, kl: KeyLine) -> None:
        raise NotImplementedError

    def failed(self, key: str) -> None:
        """A line of `key` had a problem: later checks must not complain it is missing."""

    def unknown(self, kl: KeyLine, known: frozenset[str] | set[str], where: str) -> LineError:
        meant = closest(kl.key, known)
        if meant:  # the key meant is not missing, it is misspelt
            self.failed(meant)
        hint = f" (did you mean '{meant}'?)" if meant else ""
        return LineError.at(kl.loc, f"unknown key '{kl.key}' in {where}{hint}")


def _no_add(kl: KeyLine) -> None:
    if kl.add:
        raise LineError.at(kl.loc, f"'add' works on list keys only; '{kl.key}' takes one value")


class InstanceSection(Section):
    kind = "instance"
    KEYS = frozenset({"name", "manager", "documentation", "webui_auth_file"})
    IGNORED = frozenset({"enable_auto_groups", "groups_opened_default",
                         "groups_sorted_default"})

    def __init__(self, draft: InstanceDraft, evaluator: Evaluator) -> None:
        self.draft = draft
        self.evaluator = evaluator

    def key(self, p: Parser, kl: KeyLine) -> None:
        if kl.key in self.IGNORED:
            return
        if kl.key not in self.KEYS:
            raise self.unknown(kl, self.KEYS | self.IGNORED, "the instance section")
        _no_add(kl)
        v = p.scalar(kl)
        if kl.key == "name":
            size = len(v.text.encode("utf-8", "surrogateescape"))
            if not 1 <= size <= 200 or not v.text.isprintable():
                raise fail(v, "instance name must be 1..200 bytes of printable characters")
            self.draft.name = p.evaluator.instance_name = v.text
        elif kl.key == "manager":
            self.draft.manager = p.evaluator.manager = parse_address(v, "manager")
        elif kl.key == "documentation":
            self.draft.documentation = v.text
        else:
            self.draft.webui_auth_file = p.path(v.text, kl)

    def failed(self, key: str) -> None:
        self.draft.failed.add(key)
        if key in ("name", "manager"):
            self.evaluator.broken.add("instance_name" if key == "name" else key)


class DefinesSection(Section):
    kind = "defines"
    general_keys = True

    def __init__(self, evaluator: Evaluator) -> None:
        self.evaluator = evaluator

    def failed(self, key: str) -> None:
        self.evaluator.broken.add(key.strip())

    def key(self, p: Parser, kl: KeyLine) -> None:
        _no_add(kl)
        name = p.expand_key(kl)
        if not DEFINE_NAME_RE.match(name):
            raise LineError.at(kl.loc, f"bad define name '{name}' (letters, digits, _ . - /, "
                                       "not starting with a digit)")
        if name in BUILTINS:
            raise LineError.at(kl.loc, f"'{name}' is builtin and cannot be defined")
        value = p.scalar(kl)
        if name not in p.evaluator.fixed:  # given by the caller: it wins
            p.evaluator.defines[name] = value.text
            p.evaluator.broken.discard(name)


class HostsSection(Section):
    kind = "hosts"
    general_keys = True

    def key(self, p: Parser, kl: KeyLine) -> None:
        _no_add(kl)
        name = p.expand_key(kl)
        if not HOST_NAME_RE.match(name):
            raise LineError.at(kl.loc, f"bad host name '{name}'")
        host = p.drafts.hosts.setdefault(name, Host(name, kl.loc))
        problems = []
        for v in p.values(kl):
            for item in split_value(v):
                try:
                    self._setting(host, item)
                except LineError as exc:
                    problems.extend(exc.problems)
        if problems:
            raise LineError(problems)

    @staticmethod
    def _setting(host: Host, item: Value) -> None:
        name, colon, text = item.text.partition(":")
        if not colon or not re.match(r"[A-Za-z_][A-Za-z0-9_.\-]*\Z", name.strip()):
            raise fail(item, f"host setting '{item.text}' must be SETTING:VALUE")
        raw, quoted = unquote(text.strip())
        offset = len(name) + 1 + len(text) - len(text.lstrip()) + int(quoted)
        value = Value(raw, item.at(offset), item.exact and not quoted)
        name = name.strip()
        if name == "process_start_rate_limit":
            host.process_start_rate_limit = parse_float(value, name, 0.0, above=True)
        elif name == "daemon_port":
            host.daemon_port = parse_int(value, name, 1, 65535)
        elif name == "daemon_start_script":
            if not value.text:
                raise fail(value, "'daemon_start_script' needs a value")
            host.daemon_start_script = value.text
        else:
            host.interfaces[name] = parse_ipv4(value, name)


class NodeMapSection(Section):
    kind = "node_map"
    general_keys = True

    def key(self, p: Parser, kl: KeyLine) -> None:
        _no_add(kl)
        name = p.expand_key(kl)
        if not HOST_NAME_RE.match(name):
            raise LineError.at(kl.loc, f"bad node name '{name}'")
        v = p.scalar(kl)
        if not HOST_NAME_RE.match(v.text):
            raise fail(v, f"node '{name}' must map to a host name, got '{v.text}'")
        p.drafts.node_map[name] = v.text


class ProcessSection(Section):
    kind = "process"

    def __init__(self, draft: ProcessDraft) -> None:
        self.draft = draft

    def key(self, p: Parser, kl: KeyLine) -> None:
        process_key(self.draft, kl, p)

    def failed(self, key: str) -> None:
        self.draft.failed.add(key)


class StateSection(Section):
    kind = "state"
    KEYS = frozenset({"check", "up", "down", "node", "min_check_interval"})
    UNSUPPORTED = frozenset({"tcp_tunnel_exit_target", "tcp_tunnel_exit_node",
                             "tcp_tunnel_entry_port"})

    def __init__(self, draft: StateDraft) -> None:
        self.draft = draft

    def key(self, p: Parser, kl: KeyLine) -> None:
        if kl.key == "documentation":
            return
        if kl.key in self.UNSUPPORTED:
            raise LineError.at(kl.loc, "TCP tunnel states of the original Links and Nodes "
                                       f"are not supported ('{kl.key}')")
        if kl.key not in self.KEYS:
            raise self.unknown(kl, self.KEYS | {"documentation"},
                               f"state '{self.draft.state.name}'")
        _no_add(kl)
        v = p.scalar(kl)
        state = self.draft.state
        if kl.key == "min_check_interval":
            state.min_check_interval = parse_duration(v, kl.key)
            return
        if not v.text.strip():
            raise fail(v, f"'{kl.key}' needs a value")
        if kl.key == "node":
            if any(c.isspace() for c in v.text):
                raise fail(v, f"'node' must be one word, got '{v.text}'")
            state.node = v.text
        elif kl.key == "check":
            state.check = v.text
            self.draft.has_check = True
        else:
            setattr(state, kl.key, v.text)

    def failed(self, key: str) -> None:
        self.draft.failed.add(key)


class GroupSection(Section):
    kind = "group"
    KEYS = frozenset({"members", "flags", "documentation"})

    def __init__(self, draft: GroupDraft) -> None:
        self.draft = draft

    def key(self, p: Parser, kl: KeyLine) -> None:
        if kl.key == "documentation":
            return
        if kl.key not in self.KEYS:
            raise self.unknown(kl, self.KEYS, f"group '{self.draft.group.name}'")
        values = p.values(kl)
        if kl.key == "members":
            refs = ref_items(values, kl, exclusions=True)
            if not kl.add:
                self.draft.members.clear()
            self.draft.members.extend(refs)
            return
        flags, problems = [], []
        for item in (i for v in values for i in split_value(v, ", \t")):
            if item.text in GROUP_FLAGS:
                flags.append(item.text)
            else:
                problems.append(Problem(item.loc, f"unknown flag '{item.text}' in group "
                                        f"'{self.draft.group.name}'"
                                        f"{did_you_mean(item.text, GROUP_FLAGS)}"))
        if problems:
            raise LineError(problems)
        if not kl.add:
            self.draft.group.flags.clear()
        self.draft.group.flags.update(flags)

    def failed(self, key: str) -> None:
        self.draft.failed.add(key)


class TemplateSection(Section):
    """Records its lines unread; they are read where the template is used."""

    kind = "template"

    def __init__(self, template: Template) -> None:
        self.template = template


class BrokenSection(Section):
    """A section whose header had a problem: its lines are skipped without more noise."""

    kind = "broken"

    def key(self, p: Parser, kl: KeyLine) -> None:
        return
