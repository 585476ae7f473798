"""The --ros2 mapping, checked by a plain Zenoh session (no ROS 2 can be installed here):
rmw_zenoh's data keys with the md's ROS 2 type and RIHS01 hash, CDR payloads that two
independent decoders (mcap-ros2-support, rosbags) read to the published values, rmw_zenoh's
33-byte attachment, and @ros2_lv liveliness tokens of the bridge's node and of each topic's
publisher."""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path

from buildtree import missing_test_tool
from zenoh_sites import Site, log_text, wait_log

from links_and_nodes import ros2 as ln_ros2

MD_DIRS = [str(Path(__file__).resolve().parent / "md")]
HASH = r"RIHS01_[0-9a-f]{64}"


def _decoders() -> tuple:  # type: ignore[type-arg]
    """(mcap-ros2-support's decoder, a rosbags type store) of zbtest/sample's ROS 2 type."""
    try:
        from mcap.records import Schema
        from mcap_ros2.decoder import DecoderFactory
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore
    except ImportError:
        missing_test_tool("the PyPI packages mcap-ros2-support and rosbags (requirements-dev.txt)")
    schema = ln_ros2.msg_schema("zbtest/sample", MD_DIRS)
    mcap = DecoderFactory().decoder_for(
        "cdr", Schema(id=1, name="zbtest/msg/Sample", encoding="ros2msg", data=schema.encode()))
    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg(schema, "zbtest/msg/Sample"))
    return mcap, store


def test_ros2_keys_cdr_payloads_and_tokens(sites: tuple[Site, Site]) -> None:
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
    type_hash = ln_ros2.rihs01("zbtest/sample", MD_DIRS)
    pub_tokens = [t for t in tokens if "/MP/" in t]
    assert len(pub_tokens) == 1, tokens
    m = re.fullmatch(rf"@ros2_lv/7/[0-9a-f]+/0/\d+/MP/%/%/{node}/%zb%state/"
                     rf"zbtest::msg::dds_::Sample_/({HASH})/::,1:,:,:,,", pub_tokens[0])
    assert m, pub_tokens[0]
    assert m.group(1) == type_hash
    assert len(samples) == 5
    gid = hashlib.sha256(pub_tokens[0].encode()).digest()[:16].hex()
    mcap, store = _decoders()
    for sample in samples:
        assert sample["key"] == f"7/zb/state/zbtest::msg::dds_::Sample_/{type_hash}"
        assert sample["encoding"] == "zenoh/bytes"
        payload = bytes.fromhex(sample["payload"])
        assert payload[:4] == b"\x00\x01\x00\x00"  # little-endian CDR
        by_mcap = mcap(payload)
        by_rosbags = store.deserialize_cdr(payload, "zbtest/msg/Sample")
        counter = by_mcap.counter
        assert (by_mcap.counter, by_mcap.value) == (counter, counter * 0.5)
        assert (by_rosbags.counter, by_rosbags.value) == (counter, counter * 0.5)
        assert sample["seq"] == counter, "the attachment carries the topic's sequence number"
        assert sample["time_ns"] > 0 and sample["gid"] == gid
    counters = [s["seq"] for s in samples]
    assert counters == sorted(set(counters))
    wait_log(a.procs[1], r"ROS 2 key 7/zb/state/.*: a subscriber matches")
