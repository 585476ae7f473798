"""Reads `.lnc` files line by line, filling the drafts: files and the units of lines that
name prefixes live in, the dispatch of each line to a section header (section_headers.py), a
directive (directives.py), a template use (template_use.py) or a key of the current section,
`%()` expansion of values and the names processes, states and groups share.

An included file starts in the section of its include line (so it can hold keys of the
process that includes it); sections it opens end with it, and after the include line the
including file's section goes on.  A problem skips its line and is recorded; reading goes
on so that one run reports every problem of every file.  Where the original Links and
Nodes was lenient (a missing message definition directory), a warning is recorded instead.
"""

from __future__ import annotations

import dataclasses
import os
import re

from .directives import DIRECTIVES, WORD_RE, Directives
from .drafts import Ctx, Drafts, KeyLine
from .errors import Gather, LineError, Problem, describe, did_you_mean, shift
from .expand import Evaluator
from .language import LANGUAGE_VERSION
from .lexer import SECTION_WORDS, RawLine, decode, lex
from .model import Location
from .process_keys import KNOWN as PROCESS_KEYS
from .section_headers import SectionHeaders
from .sections import BrokenSection, ProcessSection, Section, TemplateSection
from .template_use import TemplateUse
from .templates import Template
from .text import Piece, Value, find_top, unquote

_KEY_RE = re.compile(r"(add\s+)?([A-Za-z_][A-Za-z0-9_]*)\s*:")
_APPEND_RE = re.compile(r"append\s+environment\b\s*:?\s*([A-Za-z_][A-Za-z0-9_]*)\s*[:=]")
# Directives that end a template's body instead of being recorded in it.
_FILE_DIRECTIVE_RE = re.compile(r"(optional_)?include(_glob)?(\s|:|$)|(push|pop)_name_prefix"
                                r"(\s|:|$)|requires_version(\s|:|$)")


class Parser(SectionHeaders, Directives, TemplateUse):
    """The reader of one configuration and its includes.  This class holds the state and
    reads files, lines, keys and values; section headers, directives and template uses are
    its parts in section_headers.py, directives.py and template_use.py."""

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
        m = WORD_RE.match(line.text)
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
        m = WORD_RE.match(text)
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
