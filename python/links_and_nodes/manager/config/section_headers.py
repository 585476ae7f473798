"""Section headers of `.lnc` files, a part of the Parser (parser.py): `process NAME`,
`state`, `group`, `template NAME(PARAMS)`, `network`, `logger` and the sections without a
name; each opens the section object (sections.py) that takes the keys after it."""

from __future__ import annotations

import re

from .access_rules import AccessSection
from .drafts import Ctx, Drafts, GroupDraft, InstanceDraft, NetworkDraft, ProcessDraft, StateDraft
from .errors import LineError, describe, shift
from .expand import Evaluator
from .lexer import RawLine
from .model import Group, Location, Logger, Network, Process, State
from .sections import (
    NETWORK_NAME_RE,
    BrokenSection,
    DefinesSection,
    GroupSection,
    HostsSection,
    InstanceSection,
    LoggerSection,
    NetworkSection,
    NodeMapSection,
    ProcessSection,
    Section,
    StateSection,
    TemplateSection,
    TopicsSection,
)
from .templates import Template, parse_header
from .text import Piece

BAD_NAME_RE = re.compile(r"[,*?\[\]!\"%#\x00-\x1f\x7f]|^/|/$|//")
_SIMPLE_SECTIONS = frozenset({"instance", "defines", "hosts", "node_map", "topics",
                              "access"})  # no name


class SectionHeaders:
    """The Parser's section headers; uses its state (below) and its `value`, `full_name` and
    `_claim`."""

    drafts: Drafts
    evaluator: Evaluator
    section: Section | None
    templates: dict[str, Template]

    def header(self, word: str, line: RawLine, ctx: Ctx) -> None:
        self.section = BrokenSection()
        rest = line.text[len(word):]
        rest_loc = shift(line.loc, len(word) + len(rest) - len(rest.lstrip()))
        rest = rest.strip()
        if word in _SIMPLE_SECTIONS:
            if rest:
                raise LineError.at(rest_loc, f"section '{word}' takes no name")
            self.section = self._simple_section(word, line.loc)
            return
        if not rest:
            raise LineError.at(line.loc, f"section '{word}' needs a name")
        if word in ("template", "process_template"):
            name, params = parse_header(rest, rest_loc)
            full = self.full_name(name)
            if full in self.templates:
                where = describe(self.templates[full].loc, line.loc.file, self.drafts.root)
                raise LineError.at(rest_loc, f"duplicate template '{full}' "
                                             f"(first defined at {where})")
            template = Template(full, rest_loc, params)
            self.templates[full] = template
            self.section = TemplateSection(template)
            return
        name = self.value(Piece(rest, rest_loc), ctx).text.strip()
        if word == "network":
            self.network(name, line.loc, rest_loc)
            return
        if word == "logger":
            self.logger(name, line.loc, rest_loc)
            return
        if not name or BAD_NAME_RE.search(name):
            raise LineError.at(rest_loc, f"bad {word} name '{name}' (no , * ? [ ] ! \" % # "
                                         "or control characters; '/' only between parts)")
        full = self.full_name(name)
        self._claim(word, full, rest_loc)
        if word == "process":
            self.evaluator.process = (name, full)
            pdraft = ProcessDraft(Process(full, line.loc, command=""), rest_loc)
            self.drafts.processes[full] = pdraft
            self.drafts.order.append(full)
            self.section = ProcessSection(pdraft)
        elif word == "state":
            sdraft = StateDraft(State(full, line.loc, check=""), rest_loc)
            self.drafts.states[full] = sdraft
            self.drafts.order.append(full)
            self.section = StateSection(sdraft)
        else:
            gdraft = GroupDraft(Group(full, line.loc), rest_loc)
            self.drafts.groups[full] = gdraft
            self.section = GroupSection(gdraft)

    def logger(self, name: str, loc: Location, name_loc: Location) -> None:
        """A `logger NAME` header.  Loggers are not prefixed: a manager has one set."""
        if not NETWORK_NAME_RE.match(name):  # the same rules as for networks
            raise LineError.at(name_loc, f"bad logger name '{name}' (letters, digits, "
                                         "_ . -)")
        first = self.drafts.loggers.get(name)
        if first is not None:
            where = describe(first.location, loc.file, self.drafts.root)
            raise LineError.at(name_loc, f"duplicate logger '{name}' (first defined at "
                                         f"{where})")
        logger = Logger(name, loc)
        self.drafts.loggers[name] = logger
        self.section = LoggerSection(logger)

    def network(self, name: str, loc: Location, name_loc: Location) -> None:
        """A `network NAME` header.  Networks are not prefixed: they describe hosts."""
        if not NETWORK_NAME_RE.match(name):
            raise LineError.at(name_loc, f"bad network name '{name}' (letters, digits, "
                                         "_ . -)")
        first = self.drafts.networks.get(name)
        if first is not None:
            where = describe(first.name_loc, loc.file, self.drafts.root)
            raise LineError.at(name_loc, f"duplicate network '{name}' (first defined at "
                                         f"{where})")
        draft = NetworkDraft(Network(name, loc), name_loc)
        self.drafts.networks[name] = draft
        self.section = NetworkSection(draft)

    def _simple_section(self, word: str, loc: Location) -> Section:
        if word == "instance":
            if self.drafts.instance is None:
                self.drafts.instance = InstanceDraft(loc)
            return InstanceSection(self.drafts.instance, self.evaluator)
        if word == "defines":
            return DefinesSection(self.evaluator)
        if word == "topics":
            return TopicsSection()
        if word == "access":
            return AccessSection()
        return HostsSection() if word == "hosts" else NodeMapSection()
