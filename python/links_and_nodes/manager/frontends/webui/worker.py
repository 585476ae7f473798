"""Running the blocking libln side of the introspection and parameter tools (one libln
client each, connected to the manager's own port) in worker threads, with their CONTROL
commands handed back to the manager's loop."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

CONTROL_WAIT = 60.0


def loop_control(control: Any, loop: asyncio.AbstractEventLoop,
                 error: type[Exception]) -> Callable[..., dict[str, Any]]:
    """control(op, **fields) for a worker thread: Control.handle run on `loop`; a refusal
    raises `error` with its text."""
    from ..control import ControlError

    def call(op: str, **fields: Any) -> dict[str, Any]:
        future = asyncio.run_coroutine_threadsafe(control.handle({"op": op, **fields}), loop)
        try:
            return future.result(CONTROL_WAIT)
        except ControlError as exc:
            raise error(str(exc)) from None
        except TimeoutError:
            future.cancel()
            raise error(f"no answer to {op} from the manager in time") from None

    return call


async def in_thread(func: Callable[..., Any], *args: Any) -> Any:
    return await asyncio.to_thread(func, *args)
