"""Loads mds by name, resolves imports and types, and computes their layout.

The registry turns syntax trees into the typed model. It caches every md it has
loaded, detects import cycles, gathers all errors of a file before raising, and
keeps the warnings of every file it read in `.warnings`.
"""

from __future__ import annotations

import difflib
from pathlib import Path

from .diagnostics import Diagnostic, Location, MdError
from .layout import layout_hash, md_signature
from .lookup import LookupError_, default_md_dirs, find
from .model import MAX_STRUCT_SIZE, TYPE_NAMES, Field, MessageDef, Primitive, Struct
from .names import reserved_reason
from .parser import RawField, RawFile, parse

__all__ = ["MdRegistry", "default_md_dirs"]

COMMAND_LINE = "<command line>"


class MdRegistry:
    """Message definitions looked up in `md_dirs` (in order) and cached by name."""

    def __init__(self, md_dirs: list[Path] | None = None) -> None:
        self.md_dirs = list(md_dirs) if md_dirs is not None else default_md_dirs()
        self._cache: dict[str, MessageDef] = {}
        self._roots: dict[str, Path] = {}  # md name -> the md dir it was found in
        self.warnings: list[Diagnostic] = []  # of every file read, in reading order

    def load(self, name: str, where: Location | None = None) -> MessageDef:
        """The md `name`; `where` is the place that asked for it (for error messages)."""
        return self._load(name, where or Location(COMMAND_LINE, 1, 1), (), None)

    def files(self) -> list[Path]:
        """Every md file loaded so far."""
        return [md.path for md in self._cache.values()]

    def _load(
        self, name: str, where: Location, stack: tuple[str, ...], asking: str | None
    ) -> MessageDef:
        """`asking` is the md whose define names `name`: its folder is searched first."""
        beside = (self._roots[asking], asking) if asking is not None else None
        if beside is None and name in self._cache:
            return self._cache[name]
        try:
            name, root, path = find(name, self.md_dirs, beside)
        except LookupError_ as e:
            raise MdError.at(where, str(e)) from None
        if name in self._cache:
            cached = self._cache[name]
            if cached.path.resolve() != path.resolve():  # one name, two files
                raise MdError.at(
                    where,
                    f"'{path}' would be the message definition '{name}', which is already "
                    f"'{cached.path}'",
                )
            return cached
        if name in stack:
            cycle = " -> ".join([*stack[stack.index(name) :], name])
            raise MdError.at(where, f"import cycle: {cycle}")
        try:
            data = path.read_bytes()
        except OSError as e:
            raise MdError.at(where, f"cannot read '{path}': {e.strerror}") from None
        raw = parse(data, str(path))
        self.warnings += raw.warnings
        self._roots[name] = root
        md = self._resolve(name, path, raw, (*stack, name))
        self._cache[name] = md
        return md

    def _resolve(
        self, name: str, path: Path, raw: RawFile, stack: tuple[str, ...]
    ) -> MessageDef:
        errors: list[Diagnostic] = list(raw.errors)
        md = MessageDef(name, raw.kind, path, {}, doc=raw.doc)  # type: ignore[arg-type]
        for d in raw.defines:
            try:
                imported = self._load(d.md_name, d.name_loc, stack, name)
            except MdError as e:
                errors.extend(e.diagnostics)
                continue
            if imported.kind != "message":
                errors.append(
                    Diagnostic(
                        d.name_loc,
                        f"'{d.md_name}' is a {imported.kind}, not a message; "
                        "only messages can be used as field types",
                    )
                )
                continue
            md.imports[d.alias] = imported
        failed_aliases = ({d.alias for d in raw.defines} - md.imports.keys()) | raw.broken_aliases
        for section in raw.sections:
            struct = Struct(name, section.name or None)
            seen: dict[str, tuple[Location, str]] = {}
            for rf in section.fields:
                try:
                    struct.fields.append(self._field(rf, md, failed_aliases, seen))
                except MdError as e:
                    errors.extend(e.diagnostics)
            struct.layout()
            if struct.size > MAX_STRUCT_SIZE:
                errors.append(
                    Diagnostic(
                        section.loc,
                        f"{'section ' + repr(section.name) if section.name else 'message'} is "
                        f"{struct.size} bytes, more than the limit of {MAX_STRUCT_SIZE}",
                    )
                )
            md.sections[section.name] = struct
        if errors:
            here = [d for d in errors if d.loc.file == str(path)]
            elsewhere = [d for d in errors if d.loc.file != str(path)]
            raise MdError(elsewhere + sorted(here, key=lambda d: (d.loc.line, d.loc.col)))
        md.signature = md_signature(md)
        md.layout_hash = layout_hash(md)
        return md

    def _field(
        self,
        rf: RawField,
        md: MessageDef,
        failed_aliases: set[str],
        seen: dict[str, tuple[Location, str]],
    ) -> Field:
        ftype: Primitive | Struct
        if rf.type_name in md.imports:
            ftype = md.imports[rf.type_name].struct
        elif rf.type_name in TYPE_NAMES:
            ftype = TYPE_NAMES[rf.type_name]
        elif rf.type_name in failed_aliases:
            raise MdError([])  # already reported at its define line
        else:
            known = [*TYPE_NAMES, *md.imports]
            close = difflib.get_close_matches(rf.type_name, known, n=1, cutoff=0.6)
            hint = f" (did you mean '{close[0]}'?)" if close else ""
            raise MdError.at(rf.type_loc, f"unknown type '{rf.type_name}'{hint}")
        reason = reserved_reason(rf.name)
        if reason:
            raise MdError.at(rf.name_loc, reason)
        names = [(rf.name, "")]
        if rf.dynamic:
            names.append((f"{rf.name}_len", rf.name))
        for n, owner in names:
            if n in seen:
                first_loc, first_owner = seen[n]
                if first_owner:
                    what = f"field '{n}' clashes with the implicit length field of '{first_owner}'"
                elif owner:
                    what = f"implicit length field '{n}' of '{owner}' clashes with field '{n}'"
                else:
                    what = f"duplicate field '{n}'"
                raise MdError.at(rf.name_loc, f"{what} (first defined at line {first_loc.line})")
        for n, owner in names:
            seen[n] = (rf.name_loc, owner)
        if rf.dynamic:
            return Field(rf.name, ftype, "dynamic", 0, rf.name_loc, doc=rf.comment)
        if rf.count is not None:
            if rf.count * ftype.size > MAX_STRUCT_SIZE:
                raise MdError.at(
                    rf.name_loc,
                    f"array '{rf.name}' of {rf.count} elements is larger than the "
                    f"limit of {MAX_STRUCT_SIZE} bytes",
                )
            return Field(rf.name, ftype, "array", rf.count, rf.name_loc, doc=rf.comment)
        return Field(rf.name, ftype, "scalar", 1, rf.name_loc, doc=rf.comment)
