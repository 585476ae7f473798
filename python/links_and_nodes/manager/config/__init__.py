"""Reading `.lnc` configuration files into the typed model of `model.py`.

    config = load("robot.lnc", defines={"robot": "sim"})

load() reads the file and everything it includes and returns a fully resolved Config,
or raises ConfigError listing every problem of every file (`file:line:col: message`).
The language is described in docs/configuration.md.
"""

from __future__ import annotations

import os
import socket
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

from .errors import ConfigError, LineError, Problem, sort_problems
from .expand import BUILTINS, Evaluator
from .language import LANGUAGE_VERSION
from .model import Config, Location
from .parser import Parser
from .resolve import build
from .sections import DEFINE_NAME_RE
from .shell import SHELL_TIMEOUT
from .text import Value
from .values import parse_address

__all__ = ["LANGUAGE_VERSION", "Config", "ConfigError", "Location", "Problem", "Reading",
           "load", "parse_text", "read_text"]


def load(path: str | Path, *, defines: dict[str, str] | None = None,
         env: Mapping[str, str] | None = None, manager: str | None = None,
         strict: bool = False, shell_timeout: float = SHELL_TIMEOUT) -> Config:
    """Read the configuration in `path`.

    `defines` are set before the first line and win over the files' own `defines`
    lines; `env` is what `%(env NAME)` reads and what `%(shell)` commands get (default:
    os.environ); `manager` replaces the instance's `manager` address.  Problems the
    original Links and Nodes let pass are warnings in `Config.warnings`; `strict` makes
    them errors.  `shell_timeout` bounds each command the files run.  Raises
    ConfigError with every problem found, or ValueError for a bad `defines` name or
    `manager` address."""
    file = str(path)
    try:
        with open(file, "rb") as f:
            data = f.read()
    except OSError as exc:
        raise ConfigError([Problem(Location(file, 1, 1),
                                   f"cannot read configuration: {exc.strerror}")]) from None
    return parse_text(data, file, defines=defines, env=env, manager=manager, strict=strict,
                      shell_timeout=shell_timeout)


def parse_text(text: str | bytes, filename: str, *, defines: dict[str, str] | None = None,
               env: Mapping[str, str] | None = None, manager: str | None = None,
               strict: bool = False, shell_timeout: float = SHELL_TIMEOUT) -> Config:
    """Like load(), for text that claims to come from `filename` (includes and relative
    paths are resolved against its directory)."""
    reading = read_text(text, filename, defines=defines, env=env, manager=manager,
                        strict=strict, shell_timeout=shell_timeout)
    if reading.problems or reading.config is None:
        raise ConfigError(reading.problems, reading.warnings)
    reading.config.warnings = reading.warnings
    return reading.config


@dataclass
class Reading:
    """Everything one read of a configuration found: the Parser with what it collected
    (drafts, templates, names; editors point into them), the model (None when a problem
    stopped it) and the problems and warnings, sorted, as ConfigError would carry them."""

    parser: Parser
    config: Config | None
    problems: list[Problem]
    warnings: list[Problem]


def read_text(text: str | bytes, filename: str, *, defines: dict[str, str] | None = None,
              env: Mapping[str, str] | None = None, manager: str | None = None,
              strict: bool = False, shell_timeout: float = SHELL_TIMEOUT,
              make_parser: Callable[[Evaluator], Parser] = Parser) -> Reading:
    """parse_text() without raising: the whole Reading.  `make_parser` builds the Parser
    (a subclass may read included files from elsewhere, such as an editor's buffers)."""
    fixed = dict(defines or {})
    for name in fixed:
        if not DEFINE_NAME_RE.match(name) or name in BUILTINS:
            raise ValueError(f"bad define name {name!r}")
    if manager is not None:
        try:
            parse_address(Value(manager, Location("<manager>", 0, 0)), "manager")
        except LineError as exc:
            raise ValueError(exc.problems[0].message) from None
    evaluator = Evaluator(os.environ if env is None else env, fixed, socket.gethostname(),
                          manager, shell_timeout)
    parser = make_parser(evaluator)
    data = text.encode("utf-8", "surrogatepass") if isinstance(text, str) else text
    parser.read_main(filename, data)
    config, problems = build(parser.drafts, evaluator.defines, manager, filename)
    problems = parser.problems + problems
    warnings = sort_problems(parser.warnings + evaluator.warnings, parser.drafts.files)
    if strict:
        problems += [Problem(w.location, f"{w.message} [warning, an error with --strict]")
                     for w in warnings]
        warnings = []
    if problems or config is None:
        return Reading(parser, None, sort_problems(problems, parser.drafts.files), warnings)
    return Reading(parser, config, [], warnings)
