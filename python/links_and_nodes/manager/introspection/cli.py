"""`ln_manager topic echo|hz|bw|info`, `ln_manager md show`, `ln_manager service call`
(docs/introspection.md): the introspection commands as a client process of a running
manager, found like the other commands with --manager HOST:PORT or $LN_MANAGER.  Output on
stdout; an error is one line on stderr and exit status 1 (2 for usage); Ctrl-C ends a
command that follows a topic with status 0."""

from __future__ import annotations

import os
import sys
from typing import Any

from .args import GROUPS, UsageError, parse, usage
from .commands import CommandError, Context, run


def _say(text: str) -> None:
    print(text, flush=True)


def _manager(argv: list[str]) -> tuple[str | None, list[str]]:
    """--manager HOST:PORT (or --manager=HOST:PORT) anywhere, and the other words."""
    words: list[str] = []
    address = None
    it = iter(argv)
    for word in it:
        if word == "--manager":
            address = next(it, None)
            if address is None:
                raise UsageError("--manager needs HOST:PORT")
        elif word.startswith("--manager="):
            address = word.partition("=")[2]
        else:
            words.append(word)
    return address, words


def _help(group: str | None) -> str:
    return "\n".join(["usage: ln_manager [--manager HOST:PORT] COMMAND ...", "",
                      "live introspection of a running manager's topics, mds and services:",
                      *usage(group), "",
                      "the manager: --manager HOST:PORT, else $LN_MANAGER "
                      "(docs/introspection.md)"])


def main(argv: list[str]) -> int:
    prog = "ln_manager " + " ".join(argv[:2]) if argv[:1] else "ln_manager"
    if any(word in ("-h", "--help") for word in argv):
        print(_help(argv[0] if argv and argv[0] in GROUPS else None))
        return 0
    try:
        address, words = _manager(argv)
        key, args = parse(words)
    except UsageError as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    prog = f"ln_manager {key[0]} {key[1]}"
    from ..frontends.scripting import Manager, ManagerError

    address = address or os.environ.get("LN_MANAGER")
    if not address:
        print(f"{prog}: error: no manager address: give --manager HOST:PORT or set "
              "LN_MANAGER", file=sys.stderr)
        return 2
    try:
        with Manager(address, name="ln_manager_cli") as mgr:  # its clients: ln_topic_echo, ...
            def control(op: str, **fields: Any) -> dict[str, Any]:
                try:
                    return mgr.command(op, **fields)
                except ManagerError as exc:
                    raise CommandError(str(exc)) from None

            run(Context(control, mgr.address, _say), key, args)
    except (CommandError, ManagerError) as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 0
    except BrokenPipeError:  # `| head`: the reader has enough
        sys.stderr.close()
        return 0
    return 0
