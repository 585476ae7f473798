"""`param ...` in the manager's console (docs/parameters.md).  The console runs in the
manager's asyncio loop and a block's service is called from a libln client connected to the
manager's own port, so each command runs in a worker thread (as the introspection commands
do, introspect_console.Watch), its CONTROL requests handed to the loop; the console awaits it.
A file of save/load is relative to the manager's working directory."""

from __future__ import annotations

import asyncio
import threading
from typing import Any

from ..frontends.control import ControlError
from ..introspection.console import Watch
from .commands import ParamUsage, run
from .tools import ParamError, Session


async def execute(console: Any, words: list[str]) -> None:
    """Run `param WORDS...` (without the leading "param")."""
    watch = Watch(console, asyncio.get_running_loop())
    failure: list[str] = []

    def work() -> None:
        def control(op: str, **fields: Any) -> dict[str, Any]:
            try:
                return watch.control(op, **fields)
            except Exception as exc:  # CommandError from the loop: one line
                raise ParamError(str(exc)) from None

        try:
            with Session(control, watch.context.address, "ln_console_param") as session:
                run(session, words, watch.say)
        except (ParamUsage, ParamError) as exc:
            failure.append(str(exc))
        except Exception as exc:  # a bug of ours: say it, keep the manager running
            failure.append(f"internal error: {exc!r}")
        finally:
            watch.loop.call_soon_threadsafe(watch.done.set)

    threading.Thread(target=work, daemon=True, name="console-param").start()
    await watch.done.wait()
    if failure:
        raise ControlError(failure[0])
