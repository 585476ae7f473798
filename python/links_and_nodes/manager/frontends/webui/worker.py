"""Running the blocking libln side of the introspection tools (one libln client each,
connected to the manager's own port) in worker threads, with their CONTROL commands handed
back to the manager's loop."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any


async def in_thread(func: Callable[..., Any], *args: Any) -> Any:
    return await asyncio.to_thread(func, *args)
