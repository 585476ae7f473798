"""`ln_bag`: work with MCAP recordings of ln_record (docs/recording.md, "Working with
recordings: ln_bag").

    ln_bag info FILE... [--json]
    ln_bag cut FILE... -o OUT [--start TIME] [--end TIME]
    ln_bag filter FILE... -o OUT [--topic T] [--regex RE] [--exclude RE]
    ln_bag merge FILE... -o OUT [--window S]
    ln_bag convert FILE... -o OUT --encoding ros2|json|ln
    ln_bag split FILE... -o BASE (--size SIZE | --duration S)
    ln_bag export FILE... (--csv DIR | --npz FILE)

Exit status: 0 done, 1 an error (a bad input: the output holds what came before it; an
output that exists or is an input), 2 a usage error.
"""

from __future__ import annotations

import argparse
import sys
from types import ModuleType

from . import convert, cut, export, filter, info, merge, split
from .errors import BagError, UsageError
from .output import add_output_args, add_writer_args

COMMANDS: dict[str, ModuleType] = {"info": info, "cut": cut, "filter": filter, "merge": merge,
                                   "convert": convert, "split": split, "export": export}
WRITING = ("cut", "filter", "merge", "convert", "split")


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="ln_bag",
                                 description="Inspect and rework MCAP recordings.")
    sub = ap.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, module in COMMANDS.items():
        p = sub.add_parser(name, help=module.HELP, description=module.__doc__)
        p.add_argument("inputs", nargs="+", metavar="FILE", help="an MCAP recording")
        if name in WRITING:
            add_output_args(p, "BASE" if name == "split" else "FILE")
            add_writer_args(p)
        module.add_arguments(p)
        p.add_argument("-q", "--quiet", action="store_true",
                       help="print errors only (no progress, no summary line)")
    return ap


def main(argv: list[str] | None = None) -> int:
    args = parser().parse_args(argv)
    try:
        return int(COMMANDS[args.command].run(args))
    except UsageError as exc:
        print(f"ln_bag {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except BagError as exc:
        print(f"ln_bag: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("ln_bag: interrupted", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
