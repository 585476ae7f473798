"""Source locations and the error type of the generator.

Every problem in a definition is reported as `file:line:col: message` (warnings as
`file:line:col: warning: message`); an MdError carries all errors found, so one run
shows every mistake at once.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal


@dataclass(frozen=True)
class Location:
    file: str
    line: int
    col: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"


@dataclass(frozen=True)
class Diagnostic:
    loc: Location
    message: str
    severity: Literal["error", "warning"] = "error"

    def __str__(self) -> str:
        prefix = "warning: " if self.severity == "warning" else ""
        return f"{self.loc}: {prefix}{self.message}"


class MdError(Exception):
    """One or more errors in message definitions; str() gives one line per error."""

    def __init__(self, diagnostics: list[Diagnostic]) -> None:
        self.diagnostics = list(diagnostics)
        super().__init__("\n".join(str(d) for d in self.diagnostics))

    @classmethod
    def at(cls, loc: Location, message: str) -> MdError:
        return cls([Diagnostic(loc, message)])
