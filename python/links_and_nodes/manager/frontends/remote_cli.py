"""`ln_manager COMMAND ...`: the commands of the table (commands/) as subcommands talking to a
running manager through the scripting API (scripting.py).  The argparse parser is built from
the table: positional arguments, options, help, `--json`; a command's arguments are checked
by the table like a console line's; a family of commands named by phrases (`ln_manager
logger NAME add TOPIC`, `ln_manager topic echo NAME`) takes its words as the console does.
A command that runs in the client (Command.run) runs in this process, each row printed as
it comes; Ctrl-C ends one that streams (status 0).  Exit status 0 on success, 1 when the
manager refuses or cannot be reached, 2 for usage.  The client (scripting.py, the protocol's
codec) is imported when a command runs, so that listing the commands stays light."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Iterator
from typing import Any

from ...tools.commands import (
    SAME,
    ArgError,
    Command,
    ControlError,
    Local,
    commands,
    parse_words,
    to_request,
    verbs,
)
from ...tools.commands.arguments import from_texts
from ...tools.commands.local import rows, strict_json
from .commands import phrases
from .commands.views import json_lines


def _add_manager(parser: argparse.ArgumentParser, default: Any = None) -> None:
    parser.add_argument("--manager", metavar="HOST:PORT", default=default,
                        help="the manager's address (default: $LN_MANAGER)")


def _add_command(sub: Any, cmd: Command) -> None:
    text = cmd.cli_help or cmd.help
    p = sub.add_parser(cmd.cli_word, help=text, description=text)
    _add_manager(p, argparse.SUPPRESS)
    for arg in cmd.args:
        if not arg.at("cli"):
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
    if cmd.cli_run is None and not _own_json(cmd):
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
    return parser


def names() -> list[str]:
    """Every `ln_manager` subcommand of the table."""
    return [c.cli_word for c in commands() if c.cli_word and not c.phrase] + \
        phrases.families("cli")


def _own_json(cmd: Command) -> bool:
    """Whether the command reads --json itself (an argument of the CLI's), so that its view
    says what --json prints."""
    return any(a.name == "json" and a.at("cli") for a in cmd.args)


def _json_view(cmd: Command, result: dict[str, Any]) -> Any:
    if cmd.json_view is not None:
        return cmd.json_view(result)
    return {k: v for k, v in result.items() if k != "ok"}


def _local(mgr: Any) -> Local:
    """How a command that runs here asks the manager: through the connection `mgr`."""
    from ...tools.scripting import ManagerError

    def control(op: str, **fields: Any) -> dict[str, Any]:
        try:
            return dict(mgr.command(op, **fields))
        except ManagerError as exc:
            raise ControlError(str(exc)) from None

    return Local(control, mgr.address)


def _here(cmd: Command, mgr: Any, args: dict[str, Any], as_json: bool) -> Iterator[str]:
    """The lines of a command that runs in this process, each row's as it comes; a failure
    its answer reports (Command.failed) is raised after them."""
    view = cmd.cli_format or cmd.console_format or json_lines
    local = _local(mgr)
    try:
        for row in rows(cmd, local, args):
            if as_json:
                yield from json.dumps(strict_json(_json_view(cmd, row)), indent=2,
                                      ensure_ascii=False).splitlines()
            else:
                yield from view(row, args)
            failure = cmd.failed(row) if cmd.failed is not None else ""
            if failure:
                raise ControlError(failure)
    finally:
        local.close()


def run(cmd: Command, mgr: Any, args: dict[str, Any], as_json: bool) -> Iterator[str]:
    """The lines `ln_manager COMMAND` prints for checked arguments, as they come."""
    if cmd.run is not None:
        yield from _here(cmd, mgr, args, as_json)
        return
    if cmd.cli_run is not None:
        yield from cmd.cli_run(mgr, {**args, "json": as_json})
        return
    request = to_request(cmd, args)
    del request["op"]
    wait = args.get(cmd.script_wait) if cmd.script_wait else None
    result = mgr.command(cmd.name, wait=wait, **request)
    if as_json:
        yield from json.dumps(_json_view(cmd, result), indent=2).splitlines()
        return
    yield from (cmd.cli_format or cmd.console_format or json_lines)(result, args)


def _print(prog: str, cmd: Command, address: str | None, args: dict[str, Any],
           as_json: bool) -> int:
    """Run `cmd` against the manager at `address`, printing its lines as they come; the
    exit status."""
    from ...tools.scripting import ManagerError, connect

    try:
        with connect(address) as mgr:
            for line in run(cmd, mgr, args, as_json):
                print(line, flush=True)
    except (ManagerError, ControlError) as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:  # the end of a command that streams
        return 0
    except BrokenPipeError:  # `| head`: the reader has enough
        sys.stderr.close()
        return 0
    return 0


def family_main(argv: list[str]) -> int:
    """`ln_manager logger NAME add TOPIC ...`: a command of a family (argv: the family's word
    first); --json and --manager HOST:PORT anywhere."""
    prog = f"ln_manager {argv[0]}"
    words, address = [argv[0]], None
    it = iter(argv[1:])
    for word in it:
        if word == "--manager":
            address = next(it, None)
            if address is None:
                print(f"{prog}: error: --manager needs HOST:PORT", file=sys.stderr)
                return 2
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
        prog = "ln_manager " + " ".join(phrases.said(cmd))
        as_json = "--json" in rest and not _own_json(cmd)
        if as_json:
            rest = [w for w in rest if w != "--json"]
        args = parse_words(cmd, rest, "cli")
    except ArgError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    return _print(prog, cmd, address, args, as_json)


def main(argv: list[str]) -> int:
    if argv and argv[0] in phrases.families("cli"):
        return family_main(argv)
    parser = build_parser()
    ns = parser.parse_args(argv)
    cmd = next(c for c in commands() if c.cli_word == ns.command)
    prog = f"ln_manager {ns.command}"
    given = {a.name: getattr(ns, a.name, None) for a in cmd.args if a.at("cli")}
    try:
        args = from_texts(cmd, given, "cli")
    except ArgError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    return _print(prog, cmd, ns.manager, args, getattr(ns, "json", False) and
                  not _own_json(cmd))
