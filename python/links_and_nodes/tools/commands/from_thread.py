"""Calling the command table from a worker thread (the web UI's, those of the commands that
run in a client inside the manager: the console's, a JSON request's): the manager's
Control.handle run on its asyncio loop, a refusal or no answer in time raised as the
caller's own error."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

from .errors import ControlError

CONTROL_WAIT = 60.0  # seconds a worker thread waits for the loop to answer a CONTROL command


def loop_control(control: Any, loop: asyncio.AbstractEventLoop,
                 error: type[Exception]) -> Callable[..., dict[str, Any]]:
    """control(op, **fields) for a worker thread (the web UI's, a command's that runs here):
    Control.handle run on `loop`; a refusal or no answer in time raises `error`."""

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
