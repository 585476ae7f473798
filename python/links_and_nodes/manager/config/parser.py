"""Reads `.lnc` files line by line: section headers, key lines, directives (includes,
name prefixes, templates, conditionals) and `%()` expansion, filling the drafts.

An included file starts in the section of its include line (so it can hold keys of the
process that includes it); sections it opens end with it, and after the include line the
including file's section goes on.  A problem skips its line and is recorded; reading goes
on so that one run reports every problem of every file.  Where the original Links and
Nodes was lenient (a missing message definition directory), a warning is recorded instead.
"""

from __future__ import annotations

import dataclasses
import glob
import os
import re

from .drafts import (
    Ctx,
    Drafts,
    GroupDraft,
    InstanceDraft,
    KeyLine,
    NetworkDraft,
    ProcessDraft,
    StateDraft,
)
from .errors import Gather, LineError, Problem, describe, did_you_mean, relative, shift
from .expand import Evaluator
from .language import LANGUAGE_VERSION, parse_version
from .lexer import SECTION_WORDS, RawLine, decode, lex
from .model import Group, Location, Logger, Network, Process, State
from .process_keys import KNOWN as PROCESS_KEYS
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
from .templates import Template, check_arity, parse_header, split_call
from .text import Piece, Value, find_top, split_top, unquote

DIRECTIVES = ("include", "optional_include", "include_glob", "optional_include_glob",
              "push_name_prefix", "pop_name_prefix", "add_message_definition_dir",
              "use_template", "requires_version", "pipe_include",
              "add_process_default_template")
MAX_INCLUDE_DEPTH = 32
MAX_TEMPLATE_DEPTH = 32
_WORD_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_KEY_RE = re.compile(r"(add\s+)?([A-Za-z_][A-Za-z0-9_]*)\s*:")
_BAD_NAME_RE = re.compile(r"[,*?\[\]!\"%#\x00-\x1f\x7f]|^/|/$|//")
_APPEND_RE = re.compile(r"append\s+environment\b\s*:?\s*([A-Za-z_][A-Za-z0-9_]*)\s*[:=]")
# Directives that end a template's body instead of being recorded in it.
_FILE_DIRECTIVE_RE = re.compile(r"(optional_)?include(_glob)?(\s|:|$)|(push|pop)_name_prefix"
                                r"(\s|:|$)|requires_version(\s|:|$)")
_SIMPLE_SECTIONS = frozenset({"instance", "defines", "hosts", "node_map", "topics"})  # no name


class Parser:
    def __init__(self, evaluator: Evaluator, version: str = LANGUAGE_VERSION) -> None:
        self.evaluator = evaluator
        self.version = version  # of the configuration language, for requires_version
        self.drafts = Drafts()
        self.problems: list[Problem] = []
        self.warnings: list[Problem] = []
        self.section: Section | None = None
        self.prefixes: list[tuple[str, int]] = []  # (prefix, token of the run that pushed it)
        self.templates: dict[str, Template] = {}
        self.names: dict[str, tuple[str, Location]] = {}  # processes, states, groups
        self.stack: list[tuple[str, str]] = []  # files being read: (real path, path)
        self.token = 0  # of the file or template replay being read
        self._tokens = 0

    # ------------------------------------------------------------------ files

    def read_main(self, path: str, data: bytes) -> None:
        self.drafts.root = os.path.dirname(path)
        self.read_file(path, data)

    def read_file(self, path: str, data: bytes) -> None:
        if path not in self.drafts.files:
            self.drafts.files.append(path)
        text, problem = decode(data, path)
        if problem is not None:
            self.problems.append(problem)
        lines, problems = lex(text, path)
        self.problems.extend(problems)
        self.stack.append((os.path.realpath(path), path))
        section = self.section
        try:
            self.run(lines, Ctx(path))
        finally:
            self.stack.pop()
            self.section = section

    def run(self, lines: list[RawLine], ctx: Ctx) -> None:
        """Read `lines` as one unit: name prefixes pushed in it are popped at its end."""
        saved = self.token
        self._tokens += 1
        self.token = self._tokens
        for line in lines:
            self.line(line, dataclasses.replace(ctx, file=line.loc.file))
        while self.prefixes and self.prefixes[-1][1] == self.token:
            self.prefixes.pop()
        self.token = saved

    def line(self, line: RawLine, ctx: Ctx) -> None:
        if isinstance(self.section, TemplateSection):
            if self._header_word(line) is None and not _FILE_DIRECTIVE_RE.match(line.text):
                self.section.template.body.append(line)
                return
            self.section = None  # the template's body ends here
        try:
            self.dispatch(line, ctx)
        except LineError as exc:
            self.report(exc.problems, ctx)

    def report(self, problems: list[Problem], ctx: Ctx) -> None:
        note = ctx.note
        self.problems.extend(Problem(p.location, p.message + note) for p in problems)

    def warn(self, loc: Location, message: str, ctx: Ctx) -> None:
        self.warnings.append(Problem(loc, message + ctx.note))

    # ------------------------------------------------------------------ lines

    @staticmethod
    def _header_word(line: RawLine) -> str | None:
        m = _WORD_RE.match(line.text)
        if m is None or m.group() not in SECTION_WORDS:
            return None
        after = line.text[m.end():]
        if after and not after[0].isspace():
            return None
        return None if after.lstrip().startswith(":") else m.group()

    def dispatch(self, line: RawLine, ctx: Ctx) -> None:
        if line.broken:
            self._skip_broken(line)
            return
        text = line.text
        m = _WORD_RE.match(text)
        word = m.group() if m else ""
        after = text[len(word):]
        if word in DIRECTIVES and (not after or after[0] in " \t:"):
            arg = after.lstrip(" \t")
            arg = arg[1:] if arg.startswith(":") else arg
            offset = len(text) - len(arg.lstrip())
            if line.block is not None:
                raise LineError.at(line.block_loc or line.loc,
                                   f"'{word}' does not take a '[' block")
            self.directive(word, Piece(arg.strip(), shift(line.loc, offset)), line, ctx)
            return
        if word in ("ifdef", "ifndef") and after[:1] in (" ", "\t"):
            self.conditional(word, line, ctx)
            return
        if word == "append" and _APPEND_RE.match(text):
            self.append_environment(line, ctx)
            return
        header = self._header_word(line)
        if header is not None:
            self.header(header, line, ctx)
            return
        self.key_line(line, ctx, word, after)

    def append_environment(self, line: RawLine, ctx: Ctx) -> None:
        """`append environment VAR: VALUE` (the original's old syntax): VALUE is added to
        VAR's value in the process, after a ':' if VAR has one already."""
        m = _APPEND_RE.match(line.text)
        assert m is not None
        section = self.section
        if not isinstance(section, ProcessSection):
            raise LineError.at(line.loc, "'append environment' outside of a process section")
        name = m.group(1)
        rest = line.text[m.end():]
        piece = Piece(rest.strip(), shift(line.loc, m.end() + len(rest) - len(rest.lstrip())))
        if line.block is not None:
            raise LineError.at(line.block_loc or line.loc,
                               "'append environment' does not take a '[' block")
        value = self.value(piece, ctx).text
        env = section.draft.process.environment
        old = env.get(name)
        env[name] = f"{old}:{value}" if old and value else (old or value)
        section.draft.key_locs["environment"] = (piece.loc, ctx.note)

    def _skip_broken(self, line: RawLine) -> None:
        """A line whose problem the lexer reported: keep later checks quiet about it."""
        if self._header_word(line) is not None:
            self.section = BrokenSection()
            return
        m = _KEY_RE.match(line.text)
        if m is not None and self.section is not None:
            self.section.failed(m.group(2))

    def key_line(self, line: RawLine, ctx: Ctx, word: str, after: str) -> None:
        text = line.text
        section = self.section
        km = _KEY_RE.match(text)
        if section is not None and section.general_keys and not (km and km.group(1)):
            colon = find_top(text, ":")
            if colon <= 0:
                raise LineError.at(line.loc, f"expected 'NAME: VALUE' in the {section.kind} "
                                             "section")
            key, key_loc, add = text[:colon].strip(), line.loc, False
        elif km is not None:
            key, add = km.group(2), km.group(1) is not None
            key_loc = shift(line.loc, km.start(2))
            colon = km.end() - 1
        else:
            raise LineError.at(line.loc, self._unparsable(word, after))
        if line.block is not None:
            pieces = tuple(Piece(b.text, b.loc) for b in line.block)
        else:
            rest = text[colon + 1:]
            value_loc = shift(line.loc, colon + 1 + len(rest) - len(rest.lstrip()))
            pieces = (Piece(rest.strip(), value_loc),)
        kl = KeyLine(key, key_loc, add, pieces, line.block_loc, ctx, self.scopes())
        if section is None:
            raise LineError.at(key_loc, f"key '{key}' outside of a section")
        try:
            section.key(self, kl)
        except LineError:
            section.failed(key)
            raise

    def _unparsable(self, word: str, after: str) -> str:
        if word and word in self._section_keys():
            assert self.section is not None
            self.section.failed(word)
            return f"missing ':' after key '{word}'"
        if word and (not after or after[0].isspace()):
            words = (*SECTION_WORDS, *DIRECTIVES, "ifdef", "ifndef", "append")
            return f"unknown section or directive '{word}'{did_you_mean(word, words)}"
        return "expected 'KEY: VALUE', a section header or a directive"

    def _section_keys(self) -> frozenset[str]:
        section = self.section
        if isinstance(section, ProcessSection):
            return PROCESS_KEYS
        return frozenset(getattr(section, "KEYS", frozenset()))

    # ------------------------------------------------------------------ values

    def value(self, piece: Piece, ctx: Ctx) -> Value:
        """A piece unquoted and expanded."""
        text, quoted = unquote(piece.text)
        loc = shift(piece.loc, 1) if quoted else piece.loc
        out = self.evaluator.expand(text, loc, ctx.file, ctx.args)
        raw = piece.text[1:-1] if quoted else piece.text
        return Value(out, loc, out == raw)

    def values(self, kl: KeyLine) -> list[Value]:
        out, gather = [], Gather()
        for piece in kl.pieces:
            try:
                out.append(self.value(piece, kl.ctx))
            except LineError as exc:
                gather.add(exc)
        gather.check()
        return out

    def scalar(self, kl: KeyLine) -> Value:
        """The one value of a key; the lines of a block are joined by newlines."""
        values = self.values(kl)
        if kl.block_loc is None or len(values) == 1:
            return values[0]
        if not values:
            return Value("", kl.block_loc, False)
        return Value("\n".join(v.text for v in values), values[0].loc, False)

    def expand_key(self, kl: KeyLine) -> str:
        return self.value(Piece(kl.key, kl.loc), kl.ctx).text.strip()

    def path(self, text: str, kl: KeyLine) -> str:
        return self.file_path(text, kl.ctx.file, absolute=True)

    @staticmethod
    def file_path(text: str, file: str, absolute: bool = False) -> str:
        """`text` relative to the directory of `file`; `~` paths are left alone (they are
        meant for the host the process runs on)."""
        if text.startswith("~"):
            return text
        path = os.path.normpath(os.path.join(os.path.dirname(file), text))
        return os.path.abspath(path) if absolute else path

    # ------------------------------------------------------------------ names

    def scopes(self) -> tuple[str, ...]:
        """The name prefixes in effect, innermost first, ending with "" (no prefix)."""
        out = [""]
        for prefix, _ in self.prefixes:
            out.append(f"{out[-1]}/{prefix}" if out[-1] else prefix)
        return tuple(reversed(out))

    def full_name(self, name: str) -> str:
        scope = self.scopes()[0]
        return f"{scope}/{name}" if scope else name

    def _claim(self, kind: str, name: str, loc: Location) -> None:
        """Record a process, state or group name; they share one name space."""
        if name in self.names:
            other, first = self.names[name]
            where = describe(first, loc.file, self.drafts.root)
            if other == kind:
                raise LineError.at(loc, f"duplicate {kind} '{name}' (first defined at {where})")
            raise LineError.at(loc, f"{kind} '{name}' has the same name as {other} '{name}' "
                                    f"(defined at {where})")
        self.names[name] = (kind, loc)

    # ------------------------------------------------------------------ sections

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
        if not name or _BAD_NAME_RE.search(name):
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
        return HostsSection() if word == "hosts" else NodeMapSection()

    # ------------------------------------------------------------------ directives

    def conditional(self, word: str, line: RawLine, ctx: Ctx) -> None:
        """`ifdef NAME: LINE` / `ifndef NAME: LINE`; chains of them are read in a loop."""
        while True:
            colon = find_top(line.text, ":", len(word))
            if colon < 0:
                raise LineError.at(line.loc, f"'{word}' needs 'NAME: LINE'")
            raw = line.text[len(word):colon]
            name_loc = shift(line.loc, len(word) + len(raw) - len(raw.lstrip()))
            name = self.value(Piece(raw.strip(), name_loc), ctx).text.strip()
            if not name:
                raise LineError.at(line.loc, f"'{word}' needs 'NAME: LINE'")
            rest = line.sub(colon + 1)
            if not rest.text:
                raise LineError.at(line.loc, f"'{word} {name}:' needs a line after the colon")
            if self._header_word(rest) is not None:
                raise LineError.at(rest.loc, "a section header cannot be conditional")
            if self.evaluator.is_defined(name, ctx.args) != (word == "ifdef"):
                return
            m = _WORD_RE.match(rest.text)
            inner = m.group() if m else ""
            if inner in ("ifdef", "ifndef") and rest.text[len(inner):len(inner) + 1] in " \t":
                word, line = inner, rest
                continue
            self.dispatch(rest, ctx)
            return

    def directive(self, word: str, piece: Piece, line: RawLine, ctx: Ctx) -> None:
        if word == "add_process_default_template":
            raise LineError.at(line.loc, f"'{word}' of the original Links and Nodes is not "
                                         "supported by links_and_nodes (use 'use_template' "
                                         "in each process)")
        if word == "pipe_include":
            self.pipe_include(piece, line, ctx)
            return
        if word == "pop_name_prefix":
            self.pop_prefix(piece, line, ctx)
            return
        if word == "use_template":
            self.use_template(piece, ctx)
            return
        if word in ("include_glob", "optional_include_glob"):
            self.include_glob(word, piece, ctx)
            return
        v = self.value(piece, ctx)
        if not v.text:
            raise LineError.at(line.loc, f"'{word}' needs an argument")
        if word in ("include", "optional_include"):
            path = self.file_path(v.text, ctx.file)
            if not os.path.exists(path):
                if word == "include":
                    raise LineError.at(v.loc, f"included file '{v.text}' not found")
                return
            self.include(path, v)
        elif word == "push_name_prefix":
            if _BAD_NAME_RE.search(v.text) or v.text != v.text.strip():
                raise LineError.at(v.loc, f"bad name prefix '{v.text}'")
            self.prefixes.append((v.text, self.token))
        elif word == "add_message_definition_dir":
            self.add_md_dir(v, ctx)
        else:
            self.requires_version(v)

    def include(self, path: str, v: Value) -> None:
        real = os.path.realpath(path)
        if any(real == r for r, _ in self.stack):
            names = [relative(p, self.drafts.root) for _, p in self.stack]
            start = [r for r, _ in self.stack].index(real)
            chain = " -> ".join([*names[start:], relative(path, self.drafts.root)])
            raise LineError.at(v.loc, f"include cycle: {chain}")
        if len(self.stack) >= MAX_INCLUDE_DEPTH:
            raise LineError.at(v.loc, f"includes nested more than {MAX_INCLUDE_DEPTH} deep")
        try:
            with open(path, "rb") as f:
                data = f.read()
        except OSError as exc:
            raise LineError.at(v.loc, f"cannot read '{v.text}': {exc.strerror}") from None
        self.read_file(path, data)

    def pipe_include(self, piece: Piece, line: RawLine, ctx: Ctx) -> None:
        """`pipe_include COMMAND`: the command's stdout is read as if it were a file in
        the directory of the including one; its problems name the directive's place."""
        v = self.value(piece, ctx)
        command, _ = unquote(v.text.strip())
        if not command:
            raise LineError.at(line.loc, "'pipe_include' needs a command")
        if len(self.stack) >= MAX_INCLUDE_DEPTH:  # before running anything
            raise LineError.at(v.loc, f"includes nested more than {MAX_INCLUDE_DEPTH} deep")
        try:
            text = self.evaluator.run(command, ctx.file)
        except ValueError as exc:
            raise LineError.at(v.loc, str(exc)) from None
        where = f"{line.loc.file}:{line.loc.line}:{line.loc.col}"
        # A name without '/' after the including file's: CURDIR and relative paths in the
        # output are those of the including file.
        self.read_file(f"{where}: output of pipe_include",
                       text.encode("utf-8", "surrogateescape"))

    def include_glob(self, word: str, piece: Piece, ctx: Ctx) -> None:
        patterns, excluded = [], set()
        gather = Gather()
        for text, offset in split_top(piece.text, " \t"):
            try:
                v = self.value(Piece(text, shift(piece.loc, offset)), ctx)
            except LineError as exc:
                gather.add(exc)
                continue
            if v.text.startswith("!"):
                excluded.update(self._glob(v.text[1:], ctx.file))
            else:
                patterns.append(v)
        gather.check()
        if not patterns:
            raise LineError.at(piece.loc, f"'{word}' needs a file pattern")
        reading = {r for r, _ in self.stack}
        for v in patterns:
            if _searches_everything(v.text, ctx.file):
                self.report([Problem(v.loc, f"'{v.text}' would search the whole file system "
                                            "(is a define in it empty?)")], ctx)
                continue
            found = [p for p in self._glob(v.text, ctx.file) if p not in excluded]
            if not found and word == "include_glob":
                self.report([Problem(v.loc, f"no file matches '{v.text}'")], ctx)
            for path in found:
                if os.path.realpath(path) not in reading:
                    try:
                        self.include(path, Value(relative(path, self.drafts.root), v.loc))
                    except LineError as exc:
                        self.report(exc.problems, ctx)

    def _glob(self, pattern: str, file: str) -> list[str]:
        base = os.path.dirname(file)
        full = pattern if os.path.isabs(pattern) else os.path.join(glob.escape(base), pattern)
        return sorted(os.path.normpath(p) for p in glob.glob(full, recursive=True)
                      if os.path.isfile(p))

    def pop_prefix(self, piece: Piece, line: RawLine, ctx: Ctx) -> None:
        name = self.value(piece, ctx).text if piece.text else ""
        if not self.prefixes or self.prefixes[-1][1] != self.token:
            raise LineError.at(line.loc, "pop_name_prefix without a push_name_prefix before "
                                         "it in the same file")
        top = self.prefixes[-1][0]
        if name and name != top:
            raise LineError.at(piece.loc, f"pop_name_prefix '{name}' does not match the "
                                          f"innermost prefix '{top}'")
        self.prefixes.pop()

    def add_md_dir(self, v: Value, ctx: Ctx) -> None:
        path = self.file_path(v.text, ctx.file, absolute=True)
        if not os.path.isdir(path):
            self.warn(v.loc, f"message definition directory '{v.text}' not found "
                             "(ignored)", ctx)
            return
        section = self.section
        dirs = (section.draft.process.message_definition_dirs
                if isinstance(section, ProcessSection) else self.drafts.message_definition_dirs)
        if path not in dirs:
            dirs.append(path)

    def requires_version(self, v: Value) -> None:
        want = parse_version(v.text)
        if want is None:
            raise LineError.at(v.loc, f"bad version '{v.text}' (expected numbers like 0.2.43)")
        have = parse_version(self.version)
        assert have is not None
        if want > have:
            raise LineError.at(v.loc, f"this file requires version {v.text} of the Links and "
                                      "Nodes configuration language; links_and_nodes reads "
                                      f"version {self.version}")

    # ------------------------------------------------------------------ templates

    def use_template(self, piece: Piece, ctx: Ctx) -> None:
        if "%(" in piece.text:  # `use_template: %(name)`: the name is computed
            piece = Piece(self.value(piece, ctx).text.strip(), piece.loc)
        name, args = split_call(piece.text, piece.loc)
        template = self.find_template(name, piece.loc)
        if len(ctx.chain) >= MAX_TEMPLATE_DEPTH:
            raise LineError.at(piece.loc, f"templates nested more than {MAX_TEMPLATE_DEPTH} "
                                          "deep")
        if template.name in ctx.chain:
            chain = " -> ".join([*ctx.chain[ctx.chain.index(template.name):], template.name])
            raise LineError.at(piece.loc, f"template recursion: {chain}")
        given = args or []
        check_arity(template, len(given), piece.loc)
        bound: dict[str, str] = {}
        gather = Gather()
        for param, (text, offset) in zip(template.params, given, strict=False):
            try:
                bound[param.name] = self.value(Piece(text, shift(piece.loc, offset)), ctx).text
            except LineError as exc:
                gather.add(exc)
        for param in template.params[len(given):]:
            assert param.default is not None
            try:
                inner = Ctx(param.loc.file, dict(bound))
                bound[param.name] = self.value(Piece(param.default, param.loc), inner).text
            except LineError as exc:
                gather.add(exc)
        gather.check()
        where = f"{relative(piece.loc.file, self.drafts.root)}:{piece.loc.line}:{piece.loc.col}"
        use = f"template '{template.name}' used at {where}"
        self.run(template.body, Ctx(ctx.file, bound, (use, *ctx.uses),
                                    (*ctx.chain, template.name)))

    def find_template(self, name: str, loc: Location) -> Template:
        for scope in self.scopes():
            full = f"{scope}/{name}" if scope else name
            if full in self.templates:
                return self.templates[full]
        raise LineError.at(loc, f"unknown template '{name}'"
                                f"{did_you_mean(name, self._template_names())}")

    def _template_names(self) -> list[str]:
        names = list(self.templates)
        for scope in self.scopes():
            if scope:
                names += [n[len(scope) + 1:] for n in self.templates if n.startswith(scope + "/")]
        return names


def _searches_everything(pattern: str, file: str) -> bool:
    """A recursive pattern whose fixed part is the root directory, such as
    `%(EMPTY)/**/*.lnc`: globbing it would walk every mounted file system."""
    if "**" not in pattern:
        return False
    full = pattern if os.path.isabs(pattern) else os.path.join(os.path.dirname(file), pattern)
    fixed = full[:len(full) - len(full.lstrip("/"))]
    head = full.lstrip("/").split("/", 1)[0]
    return bool(fixed) and re.search(r"[*?[]", head) is not None
