"""The web UI scope of bench/realtime's background: a WebSocket client of the manager's web
UI (docs/webui.md) that subscribes one field of each topic named on the command line as
soon as that topic exists (retrying every 0.2 s), as a browser's scope would, and prints
{"events": N, "samples": M, "subscribed": [...], "refused": {topic: why}} when SIGTERM ends it.

usage: rt_scope.py URL TOPIC:FIELD..."""

from __future__ import annotations

import asyncio
import json
import re
import signal
import sys
import urllib.request
from typing import Any

from websockets.asyncio.client import connect

RETRY = 0.2  # seconds between attempts to subscribe a topic that does not exist yet


def session(url: str) -> str:
    """The session cookie the page hands out (no auth file: open on loopback)."""
    with urllib.request.urlopen(url, timeout=30) as page:
        cookie = page.headers.get("Set-Cookie", "").split(";")[0]
        page.read()
    if not re.match(r"lnm_session=", cookie):
        raise SystemExit(f"rt_scope: {url} gave no session cookie")
    return cookie


async def run(url: str, topics: list[str], stop: asyncio.Event) -> dict[str, Any]:
    port = url.split("//", 1)[1].split("/", 1)[0]
    counts = {"events": 0, "samples": 0}
    subscribed: list[str] = []
    refused: dict[str, str] = {}  # topic -> the last answer to a subscription that failed
    ws_url = f"ws://{port}/ws"
    async with connect(ws_url, origin=f"http://{port}",  # type: ignore[arg-type]
                       additional_headers={"Cookie": session(url)}, max_size=None) as conn:
        pending = {i: t for i, t in enumerate(topics, 1)}  # "topic:field"
        waiting: dict[int, str] = {}

        async def ask() -> None:
            while not stop.is_set():
                for rid, topic in list(pending.items()):
                    if rid not in waiting:
                        waiting[rid] = topic
                        name, field = topic.rsplit(":", 1)
                        await conn.send(json.dumps({"id": rid, "op": "subscribe_topic",
                                                    "name": name, "fields": [field]}))
                await asyncio.sleep(RETRY)

        async def receive() -> None:
            async for raw in conn:
                msg = json.loads(raw)
                if msg.get("event") == "samples":
                    counts["events"] += 1
                    counts["samples"] += len(msg.get("seq", []))
                elif msg.get("id") in waiting:
                    topic = waiting.pop(msg["id"])
                    if msg.get("ok"):
                        pending.pop(msg["id"], None)
                        subscribed.append(topic)
                        refused.pop(topic, None)
                    else:
                        refused[topic] = str(msg.get("error"))

        tasks = [asyncio.create_task(ask()), asyncio.create_task(receive())]
        await stop.wait()
        for task in tasks:
            task.cancel()
    return {**counts, "subscribed": subscribed, "refused": refused}


def main() -> int:
    if len(sys.argv) < 3:
        print(__doc__.rsplit("\n\n", 1)[1], file=sys.stderr)
        return 2
    loop = asyncio.new_event_loop()
    stop = asyncio.Event()
    loop.add_signal_handler(signal.SIGTERM, stop.set)
    result = loop.run_until_complete(run(sys.argv[1], sys.argv[2:], stop))
    print(json.dumps(result), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
