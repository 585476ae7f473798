"""Problems found in `.lnc` files and the exception that carries all of them at once.

Every problem is `file:line:col: message`; load() collects them over all files and
raises one ConfigError, so a user sees every mistake of a configuration in one run.
"""

from __future__ import annotations

import difflib
import os
from collections.abc import Iterable
from dataclasses import dataclass

from .model import Location


@dataclass(frozen=True)
class Problem:
    location: Location
    message: str

    def __str__(self) -> str:
        return f"{self.location}: {self.message}"


class ConfigError(Exception):
    """One or more problems in a configuration; str() gives one line per problem.
    `warnings` are the problems found that would not have stopped the load."""

    def __init__(self, problems: Iterable[Problem],
                 warnings: Iterable[Problem] = ()) -> None:
        self.problems = list(problems)
        self.warnings = list(warnings)
        super().__init__("\n".join(str(p) for p in self.problems))


class LineError(Exception):
    """Raised while handling one line: its problems are recorded and the line is skipped."""

    def __init__(self, problems: list[Problem]) -> None:
        super().__init__("\n".join(str(p) for p in problems))
        self.problems = problems

    @classmethod
    def at(cls, loc: Location, message: str) -> LineError:
        return cls([Problem(loc, message)])


class Gather:
    """Collects the LineErrors of several parts of one line; check() raises them together.
    A LineError without problems (a part that used a name whose own line failed) still
    fails the line."""

    def __init__(self) -> None:
        self.problems: list[Problem] = []
        self.failed = False

    def add(self, exc: LineError) -> None:
        self.problems.extend(exc.problems)
        self.failed = True

    def check(self) -> None:
        if self.failed:
            raise LineError(self.problems)


def closest(word: str, candidates: Iterable[str]) -> str | None:
    close = difflib.get_close_matches(word, sorted(set(candidates)), n=1, cutoff=0.6)
    return close[0] if close else None


def did_you_mean(word: str, candidates: Iterable[str]) -> str:
    """` (did you mean 'x'?)` for the closest candidate, or ""."""
    close = closest(word, candidates)
    return f" (did you mean '{close}'?)" if close else ""


def shift(loc: Location, offset: int) -> Location:
    return Location(loc.file, loc.line, loc.col + offset)


def describe(loc: Location, from_file: str, root: str) -> str:
    """Where `loc` is, as seen from a message about `from_file`: "line 3" in the same file,
    else the file relative to the main file's directory `root` and the line."""
    if loc.file == from_file:
        return f"line {loc.line}"
    return f"{relative(loc.file, root)}:{loc.line}"


def relative(path: str, root: str) -> str:
    """`path` relative to `root` when it lies below it, else as it is."""
    try:
        rel = os.path.relpath(path, root or ".")
    except ValueError:
        return path
    return path if rel.startswith("..") else rel


def sort_problems(problems: Iterable[Problem], files: list[str]) -> list[Problem]:
    """Problems in file order (files in the order they were read), then line and column;
    exact duplicates (a template's problem replayed twice) are dropped."""
    order = {f: i for i, f in enumerate(files)}
    unique = list(dict.fromkeys(problems))
    return sorted(unique, key=lambda p: (order.get(p.location.file, len(order)),
                                         p.location.file, p.location.line, p.location.col))
