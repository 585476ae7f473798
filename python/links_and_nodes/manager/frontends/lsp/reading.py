"""One read of a configuration for the editor: the project's reader (manager/config,
`read_text`) with a Parser that takes included files from the editor's unsaved buffers and
records what editors point at: section headers, defines, includes, template uses.  The
diagnostics are those of `ln_manager check` (with its host checks)."""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field

from ...config import Reading, read_text
from ...config.drafts import Ctx
from ...config.errors import Problem
from ...config.expand import Evaluator
from ...config.lexer import RawLine
from ...config.model import Location
from ...config.parser import Parser
from ...config.sections import DefinesSection
from ...config.templates import Template
from ...config.text import Value
from .settings import Settings


@dataclass(frozen=True)
class Header:
    word: str  # process, state, group, hosts, ...
    text: str  # the whole header line as written
    loc: Location


@dataclass(frozen=True)
class DefineSite:
    name: str
    value: str
    loc: Location  # of the key


@dataclass(frozen=True)
class IncludeSite:
    loc: Location  # of the file name as written
    length: int
    target: str  # the file read


@dataclass(frozen=True)
class TemplateUseSite:
    loc: Location
    name: str
    template: Template


@dataclass
class Records:
    headers: list[Header] = field(default_factory=list)
    defines: list[DefineSite] = field(default_factory=list)
    includes: list[IncludeSite] = field(default_factory=list)
    template_uses: list[TemplateUseSite] = field(default_factory=list)
    texts: dict[str, str] = field(default_factory=dict)  # file -> the text that was read


class RecordingParser(Parser):
    """The reader's Parser; included files that are open in the editor are read from
    `buffers` (real path -> text), and what the editor features need is recorded."""

    def __init__(self, evaluator: Evaluator, buffers: Mapping[str, str]) -> None:
        super().__init__(evaluator)
        self.buffers = buffers
        self.records = Records()

    def read_file(self, path: str, data: bytes) -> None:
        text = self.buffers.get(os.path.realpath(path))
        if text is not None and path not in self.records.texts:
            data = text.encode("utf-8", "surrogatepass")
        self.records.texts.setdefault(path, data.decode("utf-8", "replace"))
        super().read_file(path, data)

    def header(self, word: str, line: RawLine, ctx: Ctx) -> None:
        self.records.headers.append(Header(word, line.text, line.loc))
        super().header(word, line, ctx)

    def include(self, path: str, v: Value) -> None:
        length = len(v.text) if v.exact else 0
        self.records.includes.append(IncludeSite(v.loc, length, os.path.abspath(path)))
        super().include(path, v)

    def find_template(self, name: str, loc: Location) -> Template:
        template = super().find_template(name, loc)
        self.records.template_uses.append(TemplateUseSite(loc, name, template))
        return template

    def key_line(self, line: RawLine, ctx: Ctx, word: str, after: str) -> None:
        if not isinstance(self.section, DefinesSection):
            super().key_line(line, ctx, word, after)
            return
        before = dict(self.evaluator.defines)
        try:
            super().key_line(line, ctx, word, after)
        finally:
            for name, value in self.evaluator.defines.items():
                if before.get(name) != value or name not in before:
                    self.records.defines.append(DefineSite(name, value, line.loc))


@dataclass
class Analysis:
    """A read of `path` (the main file) as the editor saw it."""

    path: str
    reading: Reading | None
    records: Records
    errors: list[Problem]
    warnings: list[Problem]

    @property
    def parser(self) -> RecordingParser | None:
        parser = self.reading.parser if self.reading else None
        return parser if isinstance(parser, RecordingParser) else None

    @property
    def files(self) -> list[str]:
        parser = self.parser
        return list(parser.drafts.files) if parser else [self.path]


def analyse(path: str, text: str, settings: Settings, buffers: Mapping[str, str]) -> Analysis:
    """Read `text` as the configuration `path`; never raises for what the text says."""
    def make(evaluator: Evaluator) -> Parser:
        return RecordingParser(evaluator, buffers)

    try:
        reading = read_text(text, path, defines=settings.defines, strict=settings.strict,
                            shell_timeout=settings.shell_timeout, make_parser=make)
    except ValueError as exc:  # a bad define name in the settings
        problem = Problem(Location(path, 1, 1), f"settings: {exc}")
        return Analysis(path, None, Records(), [problem], [])
    parser = reading.parser
    assert isinstance(parser, RecordingParser)
    errors, warnings = list(reading.problems), list(reading.warnings)
    if reading.config is not None:
        errors, warnings = _host_checks(reading, settings.strict)
    return Analysis(path, reading, parser.records, errors, warnings)


def _host_checks(reading: Reading, strict: bool) -> tuple[list[Problem], list[Problem]]:
    """What `ln_manager check` adds on this host (check_realtime), the same way."""
    from ..check_realtime import realtime_warnings

    assert reading.config is not None
    found = realtime_warnings(reading.config)
    if not strict:
        return [], [*reading.warnings, *found]
    return [Problem(w.location, f"{w.message} [warning, an error with --strict]")
            for w in found], list(reading.warnings)
