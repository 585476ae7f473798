"""Directives of `.lnc` files, a part of the Parser (parser.py): `ifdef`/`ifndef`, the
includes (`include`, `optional_include`, the `_glob` forms, `pipe_include`), name prefixes,
`add_message_definition_dir`, `requires_version`, and `use_template`'s entry."""

from __future__ import annotations

import glob
import os
import re

from .drafts import Ctx, Drafts
from .errors import Gather, LineError, Problem, relative, shift
from .expand import Evaluator
from .language import parse_version
from .lexer import RawLine
from .section_headers import BAD_NAME_RE
from .sections import ProcessSection, Section
from .text import Piece, Value, find_top, split_top, unquote

DIRECTIVES = ("include", "optional_include", "include_glob", "optional_include_glob",
              "push_name_prefix", "pop_name_prefix", "add_message_definition_dir",
              "use_template", "requires_version", "pipe_include",
              "add_process_default_template")
MAX_INCLUDE_DEPTH = 32
WORD_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


class Directives:
    """The Parser's directives; uses its state (below) and its `value`, `file_path`,
    `read_file`, `dispatch`, `report`, `warn`, `_header_word` and `use_template`."""

    drafts: Drafts
    evaluator: Evaluator
    section: Section | None
    prefixes: list[tuple[str, int]]
    stack: list[tuple[str, str]]
    token: int
    version: str

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
            m = WORD_RE.match(rest.text)
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
            if BAD_NAME_RE.search(v.text) or v.text != v.text.strip():
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


def _searches_everything(pattern: str, file: str) -> bool:
    """A recursive pattern whose fixed part is the root directory, such as
    `%(EMPTY)/**/*.lnc`: globbing it would walk every mounted file system."""
    if "**" not in pattern:
        return False
    full = pattern if os.path.isabs(pattern) else os.path.join(os.path.dirname(file), pattern)
    fixed = full[:len(full) - len(full.lstrip("/"))]
    head = full.lstrip("/").split("/", 1)[0]
    return bool(fixed) and re.search(r"[*?[]", head) is not None
