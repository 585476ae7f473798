"""python-ndn's NDNApp, on a UdpFace straight to our ln_daemon's pull port (no forwarder),
expresses /<prefix>/<topic>/sync (CanBePrefix, MustBeFresh) and /<prefix>/<topic>/seq=N and
gets valid Data: the names the contract says, DigestSha256 that verifies, the pull content
layout with the published sample, and an application NACK for a seq below the history."""

from __future__ import annotations

import asyncio
import ctypes
import hashlib
from typing import Any

from links_and_nodes.md_loader import message_class

from . import ndn_wire as w
from .conftest import PullLab
from .ndn_peer import ndn

TOPIC = "arm.state"


def run_app(port: int, body: Any) -> Any:
    """Run `body(app)` in a python-ndn NDNApp connected to 127.0.0.1:port; its result."""
    pkg = ndn()
    from ndn.app import NDNApp
    from ndn.security import KeychainDigest
    from ndn.transport.udp_face import UdpFace

    app = NDNApp(face=UdpFace("127.0.0.1", port), keychain=KeychainDigest())
    out: dict[str, Any] = {}

    async def main() -> None:
        try:
            out["result"] = await asyncio.wait_for(body(app, pkg.encoding), 30)
        except BaseException as exc:  # handed to the test
            out["error"] = exc
        finally:
            app.shutdown()

    app.run_forever(after_start=main())
    if "error" in out:
        raise out["error"]
    return out["result"]


def digest_ok(raw: Any) -> bool:
    d = w.decode_data(bytes(raw))
    return d.signature_type == 0 and hashlib.sha256(d.signed).digest() == d.signature


def test_python_ndn_consumer_gets_valid_data(pulllab: PullLab) -> None:
    pulllab.serve(extra=", pull_history:8")
    pulllab.publisher(TOPIC, 2000)
    pulllab.served(TOPIC)
    uri = pulllab.uri(TOPIC)

    async def body(app: Any, enc: Any) -> dict[str, Any]:
        got: dict[str, Any] = {}
        name, meta, content, raw = await app.express_interest(
            f"{uri}/sync", must_be_fresh=True, can_be_prefix=True, lifetime=2000,
            need_raw_packet=True)
        got["sync"] = (enc.Name.to_str(name), meta, bytes(content), raw)
        latest = enc.Component.to_number(name[-1])
        name, meta, content, raw = await app.express_interest(
            f"{uri}/seq={latest}", lifetime=2000, need_raw_packet=True)
        got["sample"] = (enc.Name.to_str(name), meta, bytes(content), raw, latest)
        name, meta, content, raw = await app.express_interest(
            f"{uri}/seq=1", lifetime=2000, need_raw_packet=True)  # far below 8 of history
        got["nack"] = (enc.Name.to_str(name), meta, bytes(content), raw)
        return got

    got = run_app(pulllab.port, body)
    name, meta, content, raw = got["sync"]
    assert name.startswith(f"{uri}/sync/seq=") and not meta.freshness_period
    assert digest_ok(raw)
    header = w.decode_pull_content(content)
    assert str(int.from_bytes(header[w.PULL_LATEST], "big")) == name.rsplit("=", 1)[1]
    assert len(header[w.PULL_PAYLOAD]) == ctypes.sizeof(message_class("robot/joint_state"))
    name, meta, content, raw, latest = got["sample"]
    assert name == f"{uri}/seq={latest}" and meta.freshness_period == 1000
    assert meta.content_type in (0, None) and digest_ok(raw)
    sample = w.decode_pull_content(content)
    cycle = int.from_bytes(sample[w.PULL_PAYLOAD][8:12], "little")  # after double timestamp
    assert cycle == latest and w.PULL_TIME in sample
    name, meta, content, raw = got["nack"]
    assert name == f"{uri}/seq=1" and meta.content_type == 3 and digest_ok(raw)
    assert set(w.decode_pull_content(content)) == {w.PULL_LATEST}
    _, topics = pulllab.counters()
    assert topics[TOPIC]["nacks"] >= 1 and topics[TOPIC]["syncs"] >= 1
