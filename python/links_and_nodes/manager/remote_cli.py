"""`ln_manager status|start|stop|restart|output|wait-ready|logger|quit|detach`: one function per
command, each talking to a running manager through the scripting API (scripting.py).
Exit status 0 on success, 1 when the manager refuses or cannot be reached, 2 for usage."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable

from .scripting import ManagerError, connect


def _status(args: argparse.Namespace) -> int:
    from .console import format_status

    with connect(args.manager) as mgr:
        result = mgr.command("status")
    if args.json:
        print(json.dumps(result["processes"], indent=2))
    else:
        print("\n".join(format_status(result)))
    return 0


def _start(args: argparse.Namespace) -> int:
    with connect(args.manager) as mgr:
        names = mgr.start(args.target)
        if args.wait:
            mgr.wait_ready(args.target, args.timeout)
    print(f"{'ready' if args.wait else 'starting'}: {', '.join(names)}")
    return 0


def _stop(args: argparse.Namespace) -> int:
    with connect(args.manager) as mgr:
        names = mgr.stop(args.target, force=args.force)
    print(f"stopped: {', '.join(names)}")
    return 0


def _restart(args: argparse.Namespace) -> int:
    with connect(args.manager) as mgr:
        names = mgr.restart(args.target)
    print(f"restarted: {', '.join(names)}")
    return 0


def _output(args: argparse.Namespace) -> int:
    with connect(args.manager) as mgr:
        for line in mgr.output(args.name, args.n):
            print(line)
    return 0


def _wait_ready(args: argparse.Namespace) -> int:
    with connect(args.manager) as mgr:
        mgr.wait_ready(args.target, args.timeout)
    print("ready")
    return 0


def _quit(args: argparse.Namespace) -> int:
    with connect(args.manager) as mgr:
        mgr.quit()
    return 0


def _detach(args: argparse.Namespace) -> int:
    with connect(args.manager) as mgr:
        mgr.detach()
    return 0


def _logger(args: argparse.Namespace) -> int:
    from pathlib import Path

    from .. import logger_files
    from . import logger_cli

    words = []
    for word in args.words:  # the options may also come after the words
        if word in ("--json", "--on-manager"):
            setattr(args, word[2:].replace("-", "_"), True)
        else:
            words.append(word)
    try:
        op, command = logger_cli.parse(words)
    except logger_cli.UsageError as exc:
        print(exc, file=sys.stderr)
        return 2
    with connect(args.manager) as mgr:
        if op == "logger_save" and not args.on_manager:  # written here, where the user is
            data = logger_files.download(lambda o, **a: mgr.command(o, name=command["name"],
                                                                     **a))
            try:
                result = logger_files.save(data, Path(command["path"]))
            except (OSError, ValueError) as exc:
                print(f"ln_manager logger: error: cannot save {command['path']}: {exc}",
                      file=sys.stderr)
                return 1
        else:
            if op == "logger_save":
                command["path"] = str(Path(command["path"]).absolute())
            result = mgr.command(op, **command)
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print("\n".join(logger_cli.format_result(op, command, result)))
    return 0


def _parser() -> tuple[argparse.ArgumentParser, dict[str, Callable[[argparse.Namespace], int]]]:
    parser = argparse.ArgumentParser(prog="ln_manager",
                                     description="Commands for a running ln_manager.")
    parser.add_argument("--manager", metavar="HOST:PORT",
                        help="the manager's address (default: $LN_MANAGER)")
    sub = parser.add_subparsers(dest="command", required=True)
    funcs: dict[str, Callable[[argparse.Namespace], int]] = {}

    def command(name: str, func: Callable[[argparse.Namespace], int], text: str
                ) -> argparse.ArgumentParser:
        p = sub.add_parser(name, help=text, description=text)
        p.add_argument("--manager", metavar="HOST:PORT", default=argparse.SUPPRESS,
                       help="the manager's address (default: $LN_MANAGER)")
        funcs[name] = func
        return p

    p = command("status", _status, "every process with state, pid, node and reason")
    p.add_argument("--json", action="store_true", help="as JSON")
    p = command("start", _start, "start a process, group or all (dependencies first)")
    p.add_argument("target", nargs="?", default="all")
    p.add_argument("--wait", action="store_true", help="return once they are ready")
    p.add_argument("--timeout", type=float, default=None, help="for --wait, in seconds")
    p = command("stop", _stop, "stop a process, group or all (dependents first)")
    p.add_argument("target", nargs="?", default="all")
    p.add_argument("--force", action="store_true", help="also processes with disable_stop")
    p = command("restart", _restart, "stop, then start")
    p.add_argument("target", nargs="?", default="all")
    p = command("output", _output, "recent output of a process")
    p.add_argument("name")
    p.add_argument("-n", type=int, default=20, help="lines (default 20)")
    p = command("wait-ready", _wait_ready, "wait until a process, group or all is ready")
    p.add_argument("target", nargs="?", default="all")
    p.add_argument("--timeout", type=float, default=None, help="seconds")
    p = command("logger", _logger, "topic loggers: list, add, remove, enable, disable, "
                "status, save (docs/logging.md)")
    p.add_argument("--json", action="store_true", help="the answer as JSON")
    p.add_argument("--on-manager", action="store_true",
                   help="save: write the file on the manager's host instead of here")
    p.add_argument("words", nargs=argparse.REMAINDER,
                   help="NAME add TOPIC [DEPTH] [--divisor K] [--span S] | NAME remove "
                        "[TOPIC] | NAME enable [--keep] | NAME disable | NAME status | "
                        "NAME save FILE")
    command("quit", _quit, "stop every process and end the manager")
    command("detach", _detach, "end the manager, leaving the processes running")
    return parser, funcs


COMMANDS = ("status", "start", "stop", "restart", "output", "wait-ready", "logger", "quit",
            "detach")


def main(argv: list[str]) -> int:
    parser, funcs = _parser()
    args = parser.parse_args(argv)
    try:
        return funcs[args.command](args)
    except ManagerError as exc:
        print(f"ln_manager {args.command}: error: {exc}", file=sys.stderr)
        return 1
