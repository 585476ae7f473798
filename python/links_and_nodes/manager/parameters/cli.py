"""`ln_manager param list|get|set|reset|changes|save|load` (docs/parameters.md): the parameter tools as
a client process of a running manager, found with --manager HOST:PORT or $LN_MANAGER.  Output
on stdout (--json: JSON); an error is one line on stderr and exit status 1 (2 for usage)."""

from __future__ import annotations

import os
import sys
from typing import Any

from ..introspection.cli import _manager
from ..introspection.args import UsageError
from .commands import USAGE, ParamUsage, run
from .tools import ParamError, Session


def main(argv: list[str]) -> int:
    """argv: the words after `ln_manager`, starting with "param"."""
    words = argv[1:]
    if any(word in ("-h", "--help") for word in words) or not words:
        print("usage: ln_manager [--manager HOST:PORT] " + USAGE.replace("\n", "\n       "))
        return 0 if words else 2
    try:
        address, words = _manager(words)
    except UsageError as exc:
        print(f"ln_manager param: error: {exc}", file=sys.stderr)
        return 2
    address = address or os.environ.get("LN_MANAGER")
    prog = f"ln_manager param {words[0]}" if words else "ln_manager param"
    if not address:
        print(f"{prog}: error: no manager address: give --manager HOST:PORT or set "
              "LN_MANAGER", file=sys.stderr)
        return 2
    from ..frontends.scripting import Manager, ManagerError

    try:
        with Manager(address, name="ln_manager_cli") as mgr:
            def control(op: str, **fields: Any) -> dict[str, Any]:
                try:
                    return mgr.command(op, **fields)
                except ManagerError as exc:
                    raise ParamError(str(exc)) from None

            with Session(control, mgr.address, "ln_param_cli") as session:
                run(session, words, lambda text: print(text, flush=True), can_follow=True)
    except ParamUsage as exc:
        print(f"{prog}: {exc}", file=sys.stderr)
        return 2
    except (ParamError, ManagerError) as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 1
    except BrokenPipeError:
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:  # the end of `param changes --follow`
        return 0
    return 0
