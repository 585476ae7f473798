"""Command line of the generator: `ln_generate -o OUT [--md-dir DIR] [--lang L] NAME...`.

Exit codes: 0 success, 1 an error in a message definition (every error printed
as `file:line:col: message`; nothing written), 2 a usage error. Warnings
(`file:line:col: warning: message`) go to stderr and do not change the exit code.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path

from . import __version__, emit_c, emit_cpp, emit_python, emit_rust
from .diagnostics import Diagnostic, MdError
from .lookup import ENV_DIRS, default_md_dirs
from .model import MessageDef
from .output import write_if_changed
from .registry import MdRegistry

EMITTERS: dict[str, Callable[[list[MessageDef], Path, str], str]] = {
    "c": emit_c.emit,
    "cpp": emit_cpp.emit,
    "python": emit_python.emit,
    "rust": emit_rust.emit,
}
SUFFIX_LANG = {".h": "c", ".hpp": "cpp", ".hh": "cpp", ".hxx": "cpp", ".py": "python", ".rs": "rust"}


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="ln_generate",
        description="Generate C, C++, Python or Rust types from links_and_nodes message definitions.",
        epilog=f"Definitions are looked up in the --md-dir directories in order, then in the "
        f"built-in message_definitions, then in ${ENV_DIRS} (colon-separated).",
    )
    p.add_argument("names", nargs="+", metavar="NAME", help="md names such as robot/joint_state")
    p.add_argument("-o", "--output", type=Path, help="file to write (required unless --print-deps)")
    p.add_argument("--md-dir", action="append", default=[], metavar="DIR",
                   help="directory to look up definitions in (repeatable, searched first)")
    p.add_argument("--lang", choices=sorted(EMITTERS),
                   help="output language (default: from the suffix of -o: .h, .hpp, .py, .rs)")
    p.add_argument("--print-deps", action="store_true",
                   help="print the path of every md file the names need, one per line; write nothing")
    p.add_argument("--version", action="version", version=f"ln_generate {__version__}")
    return p


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    lang = args.lang
    if not args.print_deps:
        if args.output is None:
            parser.error("-o/--output is required")
        lang = lang or SUFFIX_LANG.get(args.output.suffix)
        if lang is None:
            parser.error(f"cannot tell the language from '{args.output}'; use --lang")

    registry = MdRegistry(default_md_dirs(args.md_dir))
    mds: list[MessageDef] = []
    errors: list[Diagnostic] = []
    for name in args.names:
        try:
            mds.append(registry.load(name))
        except MdError as e:
            errors.extend(d for d in e.diagnostics if d not in errors)
    for w in registry.warnings:
        print(w, file=sys.stderr)
    try:
        if errors:
            raise MdError(errors)
        if args.print_deps:
            for path in dict.fromkeys(p.resolve() for p in registry.files()):
                print(path)
            return 0
        text = EMITTERS[lang](mds, args.output, __version__)
    except MdError as e:
        for d in e.diagnostics:
            print(d, file=sys.stderr)
        return 1
    try:
        write_if_changed(args.output, text)
    except OSError as e:
        print(f"ln_generate: cannot write '{args.output}': {e.strerror}", file=sys.stderr)
        return 1
    return 0
