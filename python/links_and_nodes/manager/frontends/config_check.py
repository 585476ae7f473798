"""`ln_manager check FILE.lnc`: load and validate a configuration without starting
anything, as a lab runs it in CI, and warn where a real-time policy cannot be applied on
this host (check_realtime).  Prints every warning and error (`file:line:col:`),
with `--print` the resolved processes as a table or `--json`; exit 0 when it loads, 1 when
it does not (with `--strict`, also when it has warnings), 2 for bad usage."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from ..config import LANGUAGE_VERSION, Config, ConfigError, Problem, load


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ln_manager check",
        description="Read a configuration and everything it includes, report every "
                    "warning and error as FILE:LINE:COL, start nothing.  Exit 0 if it "
                    f"loads, 1 if not.  Configuration language {LANGUAGE_VERSION}.")
    parser.add_argument("file", metavar="FILE.lnc", help="the configuration to check")
    parser.add_argument("-D", "--define", action="append", default=[], metavar="NAME=VALUE",
                        help="a define for the configuration (repeatable); wins over the "
                             "files' own defines")
    parser.add_argument("--strict", action="store_true",
                        help="treat every warning as an error")
    parser.add_argument("--print", dest="show", action="store_true",
                        help="print the resolved processes (name, node, command, "
                             "dependencies)")
    parser.add_argument("--json", action="store_true",
                        help="print the result as JSON: ok, errors, warnings and, with "
                             "--print, the processes")
    parser.add_argument("--shell-timeout", type=float, default=None, metavar="SECONDS",
                        help="longest a %%(shell) or pipe_include command may run "
                             "(default 10)")
    return parser


def parse_defines(parser: argparse.ArgumentParser, items: list[str]) -> dict[str, str]:
    defines = {}
    for item in items:
        name, eq, value = item.partition("=")
        if not eq or not name:
            parser.error(f"-D {item!r}: expected NAME=VALUE")
        defines[name] = value
    return defines


def main(argv: list[str]) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    defines = parse_defines(parser, args.define)
    options: dict[str, Any] = {"defines": defines, "strict": args.strict}
    if args.shell_timeout is not None:
        if not 0 < args.shell_timeout <= 3600:
            parser.error("--shell-timeout must be more than 0 and at most 3600 seconds")
        options["shell_timeout"] = args.shell_timeout
    config: Config | None = None
    errors: list[Problem] = []
    try:
        config = load(args.file, **options)
        warnings = config.warnings
        config, warnings, errors = _host_checks(config, warnings, args.strict)
    except ConfigError as exc:
        errors, warnings = exc.problems, exc.warnings
    except ValueError as exc:  # a bad -D name
        parser.error(str(exc))
    if args.json:
        result: dict[str, Any] = {
            "ok": config is not None, "language_version": LANGUAGE_VERSION,
            "errors": [_problem(p) for p in errors],
            "warnings": [_problem(p) for p in warnings]}
        if args.show and config is not None:
            result["processes"] = [_process(config, name) for name in config.processes]
        json.dump(result, sys.stdout, indent=2)
        print()
    else:
        for w in warnings:
            print(f"{w.location}: warning: {w.message}", file=sys.stderr)
        for e in errors:
            print(f"{e.location}: {e.message}", file=sys.stderr)
        if config is not None and args.show:
            print_table(config)
        if config is None:
            print(f"ln_manager check: {args.file}: {len(errors)} error"
                  f"{'' if len(errors) == 1 else 's'}", file=sys.stderr)
        else:
            print(f"ln_manager check: {args.file}: ok ({len(config.processes)} process"
                  f"{'' if len(config.processes) == 1 else 'es'}, {len(warnings)} warning"
                  f"{'' if len(warnings) == 1 else 's'})", file=sys.stderr)
    return 0 if config is not None else 1


def _host_checks(config: Config, warnings: list[Problem], strict: bool
                 ) -> tuple[Config | None, list[Problem], list[Problem]]:
    """Add what only this host can tell (check_realtime); with --strict those warnings
    are errors, as the loader's are."""
    from .check_realtime import realtime_warnings

    found = realtime_warnings(config)
    if not strict or not found:
        return config, [*warnings, *found], []
    return None, list(warnings), [Problem(w.location, f"{w.message} [warning, an error with "
                                                      "--strict]") for w in found]


def _problem(p: Problem) -> dict[str, Any]:
    loc = p.location
    return {"file": loc.file, "line": loc.line, "col": loc.col, "message": p.message}


def _process(config: Config, name: str) -> dict[str, Any]:
    p = config.processes[name]
    return {"name": p.name, "node": p.node, "command": p.command,
            "depends_on": list(p.depends_on), "start_before": list(p.start_before),
            "start_on_ready": list(p.start_on_ready), "flags": sorted(p.flags),
            "environment": dict(p.environment),
            "location": f"{p.location.file}:{p.location.line}:{p.location.col}"}


def print_table(config: Config) -> None:
    rows = [("NAME", "NODE", "DEPENDS ON", "COMMAND")]
    for p in config.processes.values():
        deps = ", ".join([*p.depends_on, *(f"{n} (start_before)" for n in p.start_before)])
        rows.append((p.name, p.node, deps or "-", p.command.replace("\n", " ")))
    widths = [max(len(r[i]) for r in rows) for i in range(3)]
    for r in rows:
        print("  ".join(c.ljust(w) for c, w in zip(r[:3], widths, strict=True)) + "  " + r[3])
