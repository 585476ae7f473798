"""The section types of a `.lnc` file and the keys each accepts (process keys live in
process_keys.py).  A section object receives the key lines written under its header."""

from __future__ import annotations

import ipaddress
import re
from collections.abc import Callable
from typing import TYPE_CHECKING

from ... import transports
from ...naming import topic_name_problem
from .drafts import (
    GroupDraft,
    HostRef,
    InstanceDraft,
    KeyLine,
    MemberRef,
    NetworkDraft,
    ProcessDraft,
    StateDraft,
)
from .errors import LineError, Problem, closest, did_you_mean
from .expand import BUILTINS, Evaluator
from .model import Host, Logger, LoggerTopic, Member, TopicSetting
from .process_keys import process_key, ref_items
from .pull_settings import PULL_KEYS, parse_pull
from .templates import Template
from .text import Value, split_value, unquote
from .values import (
    fail,
    parse_address,
    parse_duration,
    parse_float,
    parse_int,
    parse_ip,
    parse_subnet,
)

if TYPE_CHECKING:
    from .parser import Parser

DEFINE_NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_.\-/]*\Z")
HOST_NAME_RE = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.\-]*\Z")
SETTING_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_.\-]*\Z")  # host settings, interface labels
NETWORK_NAME_RE = HOST_NAME_RE
TRANSPORTS = transports.FORWARD
# Topic names (registry rules) and the fnmatch characters.
_TOPIC_PATTERN_RE = re.compile(r"[A-Za-z0-9_.:/\-*?\[\]!]+\Z")
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


SECURITY_LEVELS = ("none", "authenticate", "encrypt")


def _id_list(v: Value, key: str) -> list[str]:
    """`client_uids`/`client_gids`: user or group names and numbers, separated by spaces
    or commas; resolved to numbers where the manager runs."""
    items = [x for x in v.text.replace(",", " ").split() if x]
    if not items:
        raise fail(v, f"{key} needs at least one user or group name or number")
    return items


class InstanceSection(Section):
    kind = "instance"
    KEYS = frozenset({"name", "manager", "documentation", "webui_auth_file", "webui",
                      "webui_port", "security", "client_key_file", "client_uids",
                      "client_gids", "webui_tls_cert", "webui_tls_key"})
    PATH_KEYS = frozenset({"webui_auth_file", "client_key_file", "webui_tls_cert",
                           "webui_tls_key"})
    IGNORED = frozenset({"enable_auto_groups", "groups_opened_default",
                         "groups_sorted_default"})
    UNSUPPORTED = {"verbose2_base": "the manager's log verbosity is "
                                    "'ln_manager --log-level'"}

    def __init__(self, draft: InstanceDraft, evaluator: Evaluator) -> None:
        self.draft = draft
        self.evaluator = evaluator

    def key(self, p: Parser, kl: KeyLine) -> None:
        if kl.key in self.IGNORED:
            return
        if kl.key in self.UNSUPPORTED:
            raise LineError.at(kl.loc, f"key '{kl.key}' of the original Links and Nodes is "
                                       "not supported by links_and_nodes "
                                       f"({self.UNSUPPORTED[kl.key]})")
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
        elif kl.key == "webui":  # docs/webui.md
            if v.text not in ("on", "off", "true", "false", "yes", "no", "1", "0"):
                raise fail(v, f"webui must be on or off, not {v.text!r}")
            self.draft.webui = v.text in ("on", "true", "yes", "1")
        elif kl.key == "webui_port":
            if not v.text.isdigit() or not 0 <= int(v.text) <= 65535:
                raise fail(v, f"webui_port must be a TCP port 0..65535, not {v.text!r}")
            self.draft.webui_port = int(v.text)
        elif kl.key == "security":  # docs/security.md
            if v.text not in SECURITY_LEVELS:
                raise fail(v, "security must be none, authenticate or encrypt, not "
                              f"{v.text!r}")
            self.draft.security = v.text
        elif kl.key in ("client_uids", "client_gids"):
            setattr(self.draft, kl.key, _id_list(v, kl.key))
        else:
            setattr(self.draft, kl.key, p.path(v.text, kl))

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
        if name == "undef":
            self.undef(p, kl)
            return
        if not DEFINE_NAME_RE.match(name):
            raise LineError.at(kl.loc, f"bad define name '{name}' (letters, digits, _ . - /, "
                                       "not starting with a digit)")
        if name in BUILTINS:
            raise LineError.at(kl.loc, f"'{name}' is builtin and cannot be defined")
        value = p.scalar(kl)
        if name not in p.evaluator.fixed:  # given by the caller: it wins
            p.evaluator.defines[name] = value.text
            p.evaluator.broken.discard(name)


    def undef(self, p: Parser, kl: KeyLine) -> None:
        """`undef: NAME[, NAME...]` removes defines (one given by the caller stays: it wins
        over the files)."""
        items = [item for v in p.values(kl) for item in split_value(v, ", \t")]
        if not items:
            raise LineError.at(kl.loc, "'undef' needs the name of a define")
        problems = [Problem(item.loc, f"bad define name '{item.text}' in 'undef'")
                    for item in items if not DEFINE_NAME_RE.match(item.text)]
        if problems:
            raise LineError(problems)
        for item in items:
            if item.text not in p.evaluator.fixed:
                p.evaluator.defines.pop(item.text, None)
                p.evaluator.broken.discard(item.text)


def setting_items(p: Parser, kl: KeyLine, what: str,
                  handle: Callable[[str, Value, Value], None]) -> int:
    """Feed the `SETTING:VALUE, SETTING:VALUE` items of a hosts or topics line to
    `handle(name, item, value)` (the value unquoted, at its own column); the problems of
    all items are raised together.  Returns the number of items."""
    problems, count = [], 0
    for v in p.values(kl):
        for item in split_value(v):
            count += 1
            name, colon, text = item.text.partition(":")
            try:
                if not colon or not SETTING_RE.match(name.strip()):
                    raise fail(item, f"{what} setting '{item.text}' must be SETTING:VALUE")
                raw, quoted = unquote(text.strip())
                offset = len(name) + 1 + len(text) - len(text.lstrip()) + int(quoted)
                handle(name.strip(), item,
                       Value(raw, item.at(offset), item.exact and not quoted))
            except LineError as exc:
                problems.extend(exc.problems)
    if problems:
        raise LineError(problems)
    return count


class HostsSection(Section):
    kind = "hosts"
    general_keys = True

    def key(self, p: Parser, kl: KeyLine) -> None:
        _no_add(kl)
        name = p.expand_key(kl)
        if not HOST_NAME_RE.match(name):
            raise LineError.at(kl.loc, f"bad host name '{name}'")
        host = p.drafts.hosts.setdefault(name, Host(name, kl.loc))
        setting_items(p, kl, "host", lambda setting, _, value: self._setting(host, setting, value))

    @staticmethod
    def _setting(host: Host, name: str, value: Value) -> None:
        if name == "process_start_rate_limit":
            host.process_start_rate_limit = parse_float(value, name, 0.0, above=True)
        elif name in ("daemon_port", "data_port"):
            setattr(host, name, parse_int(value, name, 1, 65535))
        elif name == "daemon_start_script":
            if not value.text:
                raise fail(value, "'daemon_start_script' needs a value")
            host.daemon_start_script = value.text
        else:
            host.interfaces[name] = parse_ip(value, name)


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


class NetworkSection(Section):
    """`network NAME`: `member_interfaces` (HOST/IFACE, IP/BITS, `!` exclusions) and
    `preferred_gateways` (hosts).  HOST/IFACE and the gateways are checked against
    `hosts` once all files are read (resolve.py)."""

    kind = "network"
    KEYS = frozenset({"member_interfaces", "preferred_gateways"})

    def __init__(self, draft: NetworkDraft) -> None:
        self.draft = draft

    def key(self, p: Parser, kl: KeyLine) -> None:
        name = self.draft.network.name
        if kl.key not in self.KEYS:
            raise self.unknown(kl, self.KEYS, f"network '{name}'")
        values = p.values(kl)
        items = [item for v in values for item in split_value(v)]
        where = f"'{kl.key}' of network '{name}'"
        if not items:
            what = ("HOST/IFACE, IP/BITS and !EXCLUSIONS" if kl.key == "member_interfaces"
                    else "hosts")
            raise LineError.at(values[0].loc if values else kl.block_loc or kl.loc,
                               f"{where} needs a comma list of {what}")
        note = kl.ctx.note
        problems = []
        if kl.key == "preferred_gateways":
            gateways = []
            for item in items:
                if HOST_NAME_RE.match(item.text):
                    gateways.append(HostRef(item.text, item.loc, note))
                else:
                    problems.append(Problem(item.loc, f"bad host name '{item.text}' in "
                                                      f"{where}"))
            if problems:
                raise LineError(problems)
            if not kl.add:
                self.draft.gateways.clear()
            self.draft.gateways.extend(gateways)
            return
        members = []
        for item in items:
            try:
                members.append(self._member(item, where, note))
            except LineError as exc:
                problems.extend(exc.problems)
        if problems:
            raise LineError(problems)
        if not kl.add:
            self.draft.items.clear()
        self.draft.items.extend(members)
        self.draft.items_loc, self.draft.items_note = kl.loc, note

    @staticmethod
    def _member(item: Value, where: str, note: str) -> MemberRef:
        text, offset, exclude = item.text, 0, item.text.startswith("!")
        if exclude:
            rest = text[1:]
            offset = 1 + len(rest) - len(rest.lstrip())
            text = rest.strip()
            if not text:
                raise fail(item, f"'!' without HOST/IFACE or IP/BITS in {where}")
        v = Value(text, item.at(offset), item.exact)
        head, slash, tail = text.rpartition("/")
        if slash and re.match(r"[0-9]+\Z", tail):
            return MemberRef(Member(v.loc, subnet=parse_subnet(v, where)), exclude, v.loc, note)
        if slash and HOST_NAME_RE.match(head) and SETTING_RE.match(tail):
            member = Member(v.loc, host=head, interface=tail)
            return MemberRef(member, exclude, v.at(len(head) + 1), note)
        try:
            ipaddress.ip_address(text)
            hint = f"; one address is '{text}/{32 if ':' not in text else 128}'"
        except ValueError:
            hint = ""
        raise fail(v, f"bad member '{text}' in {where} (expected HOST/IFACE, IP/BITS or "
                      f"!EXCLUSION{hint})")

    def failed(self, key: str) -> None:
        self.draft.failed.add(key)


class TopicsSection(Section):
    """`PATTERN: SETTING:VALUE, ...` lines: settings of the topics a name or fnmatch glob
    matches; for each setting the first matching line in file order that has it wins."""

    kind = "topics"
    general_keys = True
    SETTINGS = ("transport", *PULL_KEYS)

    def key(self, p: Parser, kl: KeyLine) -> None:
        _no_add(kl)
        pattern = p.expand_key(kl)
        problem = topic_pattern_problem(pattern)
        if problem:
            raise LineError.at(kl.loc, problem)
        found: dict[str, str] = {}
        pull: dict[str, Value] = {}

        def handle(name: str, item: Value, value: Value) -> None:
            if name not in self.SETTINGS:
                raise fail(item, f"unknown topic setting '{name}'"
                                 f"{did_you_mean(name, self.SETTINGS)}")
            word = value.text.strip().lower()
            if name == "transport" and word not in TRANSPORTS:
                raise fail(value, f"'transport' must be udp or tcp, got '{value.text}'"
                                  f"{did_you_mean(word, TRANSPORTS)}")
            if name in found or name in pull:
                raise fail(item, f"topic setting '{name}' given twice")
            if name == "transport":
                found[name] = word
            else:
                pull[name] = value

        if not setting_items(p, kl, "topic", handle):
            values = p.values(kl)
            raise LineError.at(values[0].loc if values else kl.block_loc or kl.loc,
                               f"topic pattern '{pattern}' needs settings like "
                               f"transport:{transports.UDP} or pull:{transports.NDN_UDP}")
        p.drafts.topic_settings.append(TopicSetting(pattern, found.get("transport"), kl.loc,
                                                    parse_pull(pull, pattern)))


class LoggerSection(Section):
    """A `logger NAME` section: `autostart: true|false`, and `PATTERN: depth:N, divisor:K,
    span:DURATION` lines naming the topics it logs (docs/logging.md)."""

    kind = "logger"
    general_keys = True
    SETTINGS = ("depth", "divisor", "span")
    MAX_DEPTH = 1 << 30

    def __init__(self, logger: Logger) -> None:
        self.logger = logger

    def key(self, p: Parser, kl: KeyLine) -> None:
        _no_add(kl)
        pattern = p.expand_key(kl)
        if pattern == "autostart":
            values = p.values(kl)
            word = values[0].text.strip().lower() if len(values) == 1 else ""
            if word not in ("true", "false", "on", "off", "yes", "no", "1", "0"):
                raise LineError.at(values[0].loc if values else kl.loc,
                                   "'autostart' must be true or false")
            self.logger.autostart = word in ("true", "on", "yes", "1")
            return
        problem = topic_pattern_problem(pattern)
        if problem:
            raise LineError.at(kl.loc, problem)
        found: dict[str, float] = {}

        def handle(name: str, item: Value, value: Value) -> None:
            if name not in self.SETTINGS:
                raise fail(item, f"unknown logger setting '{name}'"
                                 f"{did_you_mean(name, self.SETTINGS)}")
            if name == "span":
                found[name] = parse_float(value, name, 0.0, above=True) \
                    if value.text.replace(".", "", 1).isdigit() else parse_duration(value, name)
            else:
                found[name] = parse_int(value, name, 1, self.MAX_DEPTH)

        if not setting_items(p, kl, "logger", handle) or "depth" not in found:
            values = p.values(kl)
            raise LineError.at(values[0].loc if values else kl.block_loc or kl.loc,
                               f"logged topic '{pattern}' needs its depth in samples, like "
                               "depth:5000 (and optionally divisor:K, span:30s)")
        self.logger.topics.append(LoggerTopic(pattern, int(found["depth"]), kl.loc,
                                              int(found.get("divisor", 1)),
                                              found.get("span", 0.0)))


def topic_pattern_problem(pattern: str) -> str | None:
    """Why `pattern` cannot stand for topics, or None: a name needs the registry's rules,
    a glob may add * ? [ ] !."""
    if not pattern:
        return "empty topic pattern"
    if not any(c in pattern for c in "*?["):
        return topic_name_problem(pattern)
    if not _TOPIC_PATTERN_RE.match(pattern):
        return (f"bad topic pattern '{pattern}' (topic names may only contain A-Z a-z 0-9 "
                "_ . : / -, patterns also * ? [ ] !)")
    return None


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
