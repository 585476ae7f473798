"""ln_foxglove's `ln.log` channel: the manager's log lines as foxglove.Log messages in JSON
(schema encoding jsonschema), so Foxglove's Log panel shows them live: a warning a client
logs with ln.LogHandler arrives with its level, text, process@host and file:line, and its
log time is the line's time."""

from __future__ import annotations

import asyncio
import json
import logging
import sys
import uuid

import links_and_nodes as ln

from .conftest import LIMIT, System
from .fox_client import connect
from .test_foxglove_live import channel


def test_log_lines_on_the_log_channel(system: System) -> None:
    text = f"gripper slipping {uuid.uuid4().hex[:8]}"

    async def run() -> None:
        client = await connect(system.foxglove_port, "foxglove.websocket.v1")
        async with client.ws:
            log_channel = await channel(client, "ln.log")
            assert (log_channel["encoding"], log_channel["schemaName"],
                    log_channel["schemaEncoding"]) == ("json", "foxglove.Log", "jsonschema")
            assert set(json.loads(log_channel["schema"])["properties"]) == {
                "timestamp", "level", "message", "name", "file", "line"}
            await client.subscribe(7, log_channel["id"])
            clnt = ln.client("fx_logger", f"127.0.0.1:{system.manager_port}")
            logger = logging.getLogger("test.foxglove.logs")
            logger.propagate = False
            handler = ln.LogHandler(clnt)
            logger.addHandler(handler)
            try:
                line = sys._getframe().f_lineno + 1
                logger.warning(text)
                handler.flush(LIMIT)
                found = await client.until(
                    lambda: [m for m in client.messages
                             if m.subscription == 7 and m.data.get("message") == text],
                    "the warning on ln.log")
            finally:
                logger.removeHandler(handler)
                clnt.close()
            m = found[0]
            assert m.data["level"] == 3  # foxglove.LogLevel WARNING
            assert m.data["name"].startswith("fx_logger@")
            assert (m.data["file"], m.data["line"]) == (__file__, line)
            stamp = m.data["timestamp"]
            assert m.log_time_ns == stamp["sec"] * 10**9 + stamp["nsec"]

    asyncio.run(run())
