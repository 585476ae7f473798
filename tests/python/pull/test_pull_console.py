"""The console's pull views against a fake Control: the "pull" part of `network` (a ports
table and a topics table with every counter, a host that cannot be asked, a refused topic)
and the `pull` listing of served topics."""

from __future__ import annotations

import io
from typing import Any

from links_and_nodes.manager.frontends.console import Console

PORT = {"address": "127.0.0.1", "port": 6363, "packets": 1041, "bad": 3, "unknown": 1,
        "other": 2, "last_error": ""}
TOPIC = {"topic": "arm.state", "name": "/ln/lab/arm.state", "ring": "r", "address": "",
         "port": 6363, "history": 64, "latest_seq": 2210, "interests": 1035, "syncs": 2,
         "data": 1033, "nacks": 4, "parked": 1021, "expired": 5, "duplicates": 6,
         "overflow": 7, "last_error": "", "error": ""}


class _Control:
    async def handle(self, command: dict[str, Any]) -> dict[str, Any]:
        if command["op"] == "pull":
            return {"ok": True, "topics": [
                {"topic": "arm.state", "host": "robot", "name": "/ln/lab/arm.state",
                 "address": "0.0.0.0", "port": 6363, "history": 64, "freshness_ms": 1000,
                 "signature": "HMAC-SHA256", "md_name": "robot/joint_state", "error": ""},
                {"topic": "cam", "host": "robot", "name": "/ln/lab/cam", "address": "0.0.0.0",
                 "port": 6363, "history": 64, "freshness_ms": 1000,
                 "signature": "DigestSha256", "md_name": "x/y",
                 "error": "message of 9000 bytes above 8000"}]}
        return {"ok": True, "streams": [], "pairs": [], "problems": [], "pull": [
            {"host": "robot", "error": "", "ports": [PORT], "topics": [TOPIC]},
            {"host": "far", "error": "the daemon cannot be reached", "ports": [],
             "topics": []}]}


async def test_network_and_pull_views() -> None:
    out = io.StringIO()
    console = Console(_Control(), out)  # type: ignore[arg-type]
    await console.execute("network")
    text = out.getvalue().splitlines()
    assert any(line.split() == ["robot", "127.0.0.1", "6363", "1041", "3", "1", "2"]
               for line in text), text
    assert any(line.split()[0] == "far" and line.endswith("the daemon cannot be reached")
               for line in text), text
    assert any(line.split() == ["arm.state", "robot", "6363", "2210", "1035", "2", "1033",
                                "4", "1021", "5", "6", "7"] for line in text), text
    out.truncate(0)
    out.seek(0)
    await console.execute("pull")
    text = out.getvalue().splitlines()
    assert text[0].split() == ["topic", "host", "name", "address", "port", "history",
                               "signature", "error"]
    assert text[1].split() == ["arm.state", "robot", "/ln/lab/arm.state", "0.0.0.0", "6363",
                               "64", "HMAC-SHA256"]
    assert text[2].endswith("message of 9000 bytes above 8000")
