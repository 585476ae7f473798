"""`ln_manager COMMAND ...`: the commands of the table (commands/) as subcommands talking to a
running manager through the scripting API (scripting.py).  The argparse parser is built from
the table: positional arguments, options, help, `--json`; a command's arguments are checked
by the table like a console line's; a family of commands named by phrases (`ln_manager
logger NAME add TOPIC`) takes its words as the console does.  Verbs with words of their own
(`topic`, `param`, ...) run their own main.  Exit status 0 on success, 1 when the manager refuses or
cannot be reached, 2 for usage."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from .commands import SAME, ArgError, Command, commands, parse_words, phrases, to_request, verbs
from .commands.check import from_texts
from .commands.views import json_lines
from .scripting import ManagerError, connect


def _add_manager(parser: argparse.ArgumentParser, default: Any = None) -> None:
    parser.add_argument("--manager", metavar="HOST:PORT", default=default,
                        help="the manager's address (default: $LN_MANAGER)")


def _add_command(sub: Any, cmd: Command) -> None:
    text = cmd.cli_help or cmd.help
    p = sub.add_parser(cmd.cli_word, help=text, description=text)
    _add_manager(p, argparse.SUPPRESS)
    for arg in cmd.args:
        if arg.where not in ("", "cli"):
            continue
        help_text = arg.help
        if arg.positional:
            p.add_argument(arg.name, nargs="?", metavar=arg.word, help=help_text)
        elif arg.type == "bool":
            p.add_argument(arg.option, dest=arg.name, action="store_true", help=help_text)
        else:
            default = arg.default if arg.text_default is SAME else arg.text_default
            if default not in (None, ""):
                help_text += f" (default {default})"
            p.add_argument(arg.option, dest=arg.name, default=None,
                           metavar=arg.metavar or arg.name[:1].upper(), help=help_text)
    if cmd.cli_run is None:
        p.add_argument("--json", action="store_true", help="the answer as JSON")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="ln_manager",
                                     description="Commands for a running ln_manager.")
    _add_manager(parser)
    sub = parser.add_subparsers(dest="command", required=True)
    for cmd in commands():
        if cmd.cli_word and not cmd.phrase:
            _add_command(sub, cmd)
    about = {v.name: v.help for v in verbs()}
    for word in phrases.families("cli"):
        text = about.get(word, word)
        sub.add_parser(word, help=text, description=text, add_help=False)
    for verb in verbs():
        if verb.cli is not None:
            sub.add_parser(verb.name, help=verb.help, description=verb.help, add_help=False)
    return parser


def names() -> list[str]:
    """Every `ln_manager` subcommand of the table."""
    return [c.cli_word for c in commands() if c.cli_word and not c.phrase] + \
        phrases.families("cli") + [v.name for v in verbs() if v.cli is not None]


def _json_view(cmd: Command, result: dict[str, Any]) -> Any:
    if cmd.json_view is not None:
        return cmd.json_view(result)
    return {k: v for k, v in result.items() if k != "ok"}


def run(cmd: Command, mgr: Any, args: dict[str, Any], as_json: bool) -> list[str]:
    """The lines `ln_manager COMMAND` prints for checked arguments."""
    if cmd.cli_run is not None:
        return cmd.cli_run(mgr, {**args, "json": as_json})
    request = to_request(cmd, args)
    del request["op"]
    wait = args.get(cmd.script_wait) if cmd.script_wait else None
    result = mgr.command(cmd.name, wait=wait, **request)
    if as_json:
        return json.dumps(_json_view(cmd, result), indent=2).splitlines()
    return (cmd.cli_format or cmd.console_format or json_lines)(result, args)


def family_main(argv: list[str]) -> int:
    """`ln_manager logger NAME add TOPIC ...`: a command of a family (argv: the family's word
    first); --json and --manager HOST:PORT anywhere."""
    prog = f"ln_manager {argv[0]}"
    words, address, as_json = [argv[0]], None, False
    it = iter(argv[1:])
    for word in it:
        if word == "--json":
            as_json = True
        elif word == "--manager":
            address = next(it, None)
        elif word.startswith("--manager="):
            address = word.split("=", 1)[1]
        elif word in ("-h", "--help"):
            about = {v.name: v.help for v in verbs()}.get(argv[0], "")
            print(phrases.usage(argv[0], "cli") + "\n  [--json] [--manager HOST:PORT]"
                  + (f"\n\n{about}" if about else ""))
            return 0
        else:
            words.append(word)
    try:
        cmd, rest = phrases.match(words, "cli")
        args = parse_words(cmd, rest, "cli")
    except ArgError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    try:
        with connect(address) as mgr:
            lines = run(cmd, mgr, args, as_json)
    except ManagerError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 1
    if lines:
        print("\n".join(lines))
    return 0


def main(argv: list[str]) -> int:
    if argv and argv[0] in phrases.families("cli"):
        return family_main(argv)
    for verb in verbs():
        if argv and argv[0] == verb.name and verb.cli is not None:
            return verb.cli(argv)
    parser = build_parser()
    ns = parser.parse_args(argv)
    cmd = next(c for c in commands() if c.cli_word == ns.command)
    prog = f"ln_manager {ns.command}"
    given = {a.name: getattr(ns, a.name, None) for a in cmd.args if a.where in ("", "cli")}
    try:
        args = from_texts(cmd, given, "cli")
    except ArgError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    try:
        with connect(ns.manager) as mgr:
            lines = run(cmd, mgr, args, getattr(ns, "json", False))
    except ManagerError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 1
    if lines:
        print("\n".join(lines))
    return 0
