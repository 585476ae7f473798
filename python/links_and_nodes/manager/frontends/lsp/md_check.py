"""The md being edited resolved as `ln_generate` resolves it when generating: its imports
looked up (beside it first, then the md directories of the settings, the built-in
`message_definitions/` and LN_MESSAGE_DEFINITION_DIRS) and its field types checked, by
ln_generate's own registry, with the editor's text in place of the saved file."""

from __future__ import annotations

from pathlib import Path

from ln_generate.diagnostics import Diagnostic, Location, MdError
from ln_generate.lookup import default_md_dirs
from ln_generate.model import MessageDef
from ln_generate.parser import RawFile
from ln_generate.registry import MdRegistry


class EditorRegistry(MdRegistry):
    """ln_generate's registry; a problem inside an md the edited one imports is shown at
    the `define` that imports it, naming its own place."""

    def __init__(self, md_dirs: list[Path], edited: str) -> None:
        super().__init__(md_dirs)
        self.edited = edited

    def _load(self, name: str, where: Location, stack: tuple[str, ...],
              asking: str | None) -> MessageDef:
        try:
            return super()._load(name, where, stack, asking)
        except MdError as exc:
            if asking != self.edited or stack != (self.edited,):
                raise
            raise MdError([d if d.loc.file == where.file else
                           Diagnostic(where, f"in '{name}': {d}", d.severity)
                           for d in exc.diagnostics]) from None

    def check(self, raw: RawFile, path: str, root: Path) -> list[Diagnostic]:
        """The problems of resolving `raw`, the text of the edited md found in `root`,
        beyond its syntax errors (imports, field types, names, sizes)."""
        self._roots[self.edited] = root
        try:
            self._resolve(self.edited, Path(path), raw, (self.edited,))
        except MdError as exc:
            return [d for d in exc.diagnostics if d not in raw.errors]
        return []


def home(path: str, dirs: list[Path]) -> tuple[Path, str]:
    """(md dir, md name) of the edited file: below one of `dirs`, else beside itself."""
    p = Path(path).resolve()
    for d in dirs:
        if p.is_relative_to(d.resolve()):
            return d, p.relative_to(d.resolve()).as_posix()
    return Path(path).parent, Path(path).name


def check(raw: RawFile, path: str, extra_dirs: list[Path]) -> list[Diagnostic]:
    dirs = default_md_dirs([str(d) for d in extra_dirs])
    root, name = home(path, dirs)
    return EditorRegistry(dirs, name).check(raw, path, root)
