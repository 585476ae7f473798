"""The --ros2 mapping, checked by a plain Zenoh session (no ROS 2 tools here): rmw_zenoh-like
data keys with JSON payloads and rmw_zenoh's 33-byte attachment, and @ros2_lv liveliness
tokens of the bridge's node and of each topic's publisher."""

from __future__ import annotations

import hashlib
import json
import re

from zenoh_sites import Site, log_text, wait_log

HASH = r"RIHS01_[0-9a-f]{64}"


def test_ros2_keys_payloads_and_tokens(sites: tuple[Site, Site]) -> None:
    a, b = sites
    a.start_manager()
    a.bridge("--listen", a.endpoint, "--out", "zb.state", "--ros2", "--ros2-domain", "7")
    a.peer("pub", "zb.state", "zbtest/sample", "--rate", "50")
    raw = b.raw("ros2", "--connect", a.endpoint, "--domain", "7", "--count", "5")
    assert raw.wait(timeout=60) == 0, log_text(raw)
    events = [json.loads(line) for line in log_text(raw).splitlines() if line.startswith("{")]
    tokens = [e["token"] for e in events if "token" in e]
    samples = [e for e in events if "key" in e]
    node = f"ln_zenoh_{a.instance}"
    assert any(re.fullmatch(rf"@ros2_lv/7/[0-9a-f]+/0/0/NN/%/%/{node}", t) for t in tokens), \
        tokens
    pub_tokens = [t for t in tokens if "/MP/" in t]
    assert len(pub_tokens) == 1, tokens
    m = re.fullmatch(rf"@ros2_lv/7/[0-9a-f]+/0/\d+/MP/%/%/{node}/%zb%state/"
                     rf"zbtest::msg::dds_::sample_/({HASH})/::,1:,:,:,,", pub_tokens[0])
    assert m, pub_tokens[0]
    assert len(samples) == 5
    gid = hashlib.sha256(pub_tokens[0].encode()).digest()[:16].hex()
    for sample in samples:
        assert sample["key"] == f"7/zb/state/zbtest::msg::dds_::sample_/{m.group(1)}"
        assert sample["encoding"] == "application/json"
        counter = sample["fields"]["counter"]
        assert sample["fields"] == {"counter": counter, "value": counter * 0.5}
        assert sample["seq"] == counter, "the attachment carries the topic's sequence number"
        assert sample["time_ns"] > 0 and sample["gid"] == gid
    counters = [s["seq"] for s in samples]
    assert counters == sorted(set(counters))
    wait_log(a.procs[1], r"ROS 2 key 7/zb/state/.*: a subscriber matches")
