"""ln_zenoh's pieces that need no network: the attachment codec and its refusals, key
expressions of names and patterns, the config file and the command line's specs, the ROS 2
mapping's formats, and the command's exit codes without zenoh and with a bad configuration
(these run with or without the zenoh package)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from zenoh_sites import require_zenoh

from links_and_nodes.ros2 import rihs01
from links_and_nodes.zenoh_bridge import ros2
from links_and_nodes.zenoh_bridge.config import (
    ConfigError,
    from_dict,
    load_file,
    service_spec,
    topic_spec,
)
from links_and_nodes.zenoh_bridge.wire import (
    Attachment,
    AttachmentEncoder,
    AttachmentError,
    bad_name,
    decode_attachment,
    decode_fields,
    name_in,
    pattern_key,
)

ROOT = Path(__file__).resolve().parents[3]


def test_attachment_round_trip_and_layout() -> None:
    att = Attachment(2**64 - 1, -5, 0x0123456789ABCDEF, "robot/joint_state")
    data = att.encode()
    assert len(data) == 29 + len("robot/joint_state")
    assert data[:4] == b"LZ\x01\x00" and data[28] == len("robot/joint_state")
    assert decode_attachment(data) == att
    assert AttachmentEncoder("robot/joint_state", 0x0123456789ABCDEF).encode(2**64 - 1, -5) \
        == data


@pytest.mark.parametrize("data, why", [
    (None, "no attachment"), (b"", "no attachment"), (b"LZ\x01", "shorter than 29"),
    (b"XX" + Attachment(1, 2, 3, "a/b").encode()[2:], "magic"),
    (b"LZ\x02" + Attachment(1, 2, 3, "a/b").encode()[3:], "version 2"),
    (Attachment(1, 2, 3, "a/b").encode()[:-1], "md name of 3"),
    (Attachment(1, 2, 3, "a/b").encode() + b"x", "md name of 3"),
    (Attachment(1, 2, 3, "a/b").encode()[:28] + b"\x01\xff", "not UTF-8"),
])
def test_attachment_refusals(data: bytes | None, why: str) -> None:
    with pytest.raises(AttachmentError, match=why):
        decode_attachment(data)


def test_names_and_patterns_as_key_expressions() -> None:
    assert bad_name("arm.state") is None and bad_name("robot/arm.state") is None
    for name in ("", "a//b", "a*", "x$y", "a?", "a#b", "@live", "a/@b"):
        assert bad_name(name), name
    assert pattern_key("*") == "**"
    assert pattern_key("arm.*") == "arm.$*"
    assert pattern_key("arm.state") == "arm.state"
    assert pattern_key("a?m.*") == "*"
    assert pattern_key("robot/*") == "robot/*"
    assert name_in("ln/a/topic/arm.state", "ln/a", "topic") == "arm.state"
    assert name_in("ln/a/topic/", "ln/a", "topic") is None
    assert name_in("ln/b/topic/x", "ln/a", "topic") is None
    assert decode_fields(b"") == {}
    with pytest.raises(ValueError):
        decode_fields(b"[1, 2]")


def test_config_file_toml_and_json(tmp_path: Path) -> None:
    toml = tmp_path / "bridge.toml"
    toml.write_text("""
prefix = "ln/site_a"
mode = "peer"
listen = ["tcp/0.0.0.0:7447"]
remote = "ln/site_b"
stats_interval = 5

[[topics]]
match = ["arm.*", "gripper.state"]
direction = "out"
rate = 100

[[topics]]
match = "log.*"
direction = "out"
queue = "queued"
buffers = 256

[[topics]]
match = "cmd.*"
direction = "in"

[[services]]
match = "arm.set_gains"
direction = "out"
""")
    config = load_file(toml)
    config.check()
    assert config.prefix == "ln/site_a" and config.listen == ["tcp/0.0.0.0:7447"]
    rule = config.topic_rule("arm.state", "out")
    assert rule is not None and rule.rate == 100.0 and not rule.queued and rule.depth == 1
    log = config.topic_rule("log.events", "out")
    assert log is not None and log.queued and log.depth == 256
    cmd = config.topic_rule("cmd.vel", "in")
    assert cmd is not None and cmd.remote == "ln/site_b"
    assert config.topic_rule("cmd.vel", "out") is None
    assert config.service_rule("arm.set_gains", "out") is not None
    js = tmp_path / "bridge.json"
    js.write_text('{"topics": [{"match": "x", "direction": "out"}], "ros2": true}')
    config = load_file(js)
    config.check()
    assert config.ros2 and config.topics[0].pattern == "x"


@pytest.mark.parametrize("data, why", [
    ({"topics": [{"match": "x", "direction": "sideways"}]}, "direction"),
    ({"topics": [{"match": "x", "direction": "in"}]}, "remote"),
    ({"topics": [{"match": "x", "direction": "out", "queue": "fifo"}]}, "queue"),
    ({"topics": [{"match": "x", "direction": "out", "colour": 1}]}, "colour"),
    ({"topics": [{"match": "x", "direction": "out", "rate": -1}]}, "rate"),
    ({"topics": [{"match": "x", "direction": "out", "queue": "queued", "buffers": 1}]},
     "buffers"),
    ({"topics": [{"direction": "out"}]}, "match"),
    ({"mode": "router", "topics": [{"match": "x", "direction": "out"}]}, "mode"),
    ({"prefix": "ln/*", "topics": [{"match": "x", "direction": "out"}]}, "prefix"),
    ({"bogus": 1}, "unknown setting"),
    ({}, "nothing to bridge"),
])
def test_config_refusals(data: dict[str, object], why: str) -> None:
    with pytest.raises(ConfigError, match=why):
        from_dict(data).check()


def test_command_line_specs() -> None:
    rule = topic_spec("log.*,queued=128,rate=50,remote=ln/b", "in")
    assert (rule.pattern, rule.queued, rule.buffers, rule.rate, rule.remote) == \
        ("log.*", True, 128, 50.0, "ln/b")
    assert topic_spec("x,queued", "out").depth == 64
    assert topic_spec("x", "out").depth == 1
    svc = service_spec("arm.*,timeout=2.5", "in")
    assert (svc.pattern, svc.timeout, svc.remote) == ("arm.*", 2.5, None)
    for bad in ("x,colour=red", "x,rate=fast", ",queued"):
        with pytest.raises(ConfigError):
            topic_spec(bad, "out")


def test_ros2_mapping_formats() -> None:
    assert ros2.ros_topic("arm.state") == "/arm/state"
    assert ros2.ros_topic("robot/arm-1.state") == "/robot/arm_1/state"
    assert ros2.ros_type("robot/joint_state") == "robot::msg::dds_::JointState_"
    assert ros2.ros_type("a/b/c") == "a_b::msg::dds_::C_"
    h = ros2.type_hash("robot/joint_state")
    assert h == rihs01("robot/joint_state")
    assert ros2.data_key(0, "arm.state", "robot/joint_state") == \
        f"0/arm/state/robot::msg::dds_::JointState_/{h}"
    gid = bytes(range(16))
    data = ros2.encode_attachment(5, 123, gid)
    assert len(data) == ros2.ATTACHMENT_SIZE == 33
    assert ros2.decode_attachment(data) == (5, 123, gid)
    with pytest.raises(ValueError):
        ros2.decode_attachment(data[:-1])


def test_ros2_attachment_is_what_zenoh_ext_serializes() -> None:
    require_zenoh()
    import zenoh.ext as ext

    gid = bytes(range(16))
    expected = ext.z_serialize((ext.Int64(5), ext.Int64(-7), gid)).to_bytes()
    assert ros2.encode_attachment(5, -7, gid) == expected


def _cli(code: str, *args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "python"), str(ROOT)])}
    return subprocess.run(
        [sys.executable, "-c", code + "\nfrom links_and_nodes.zenoh_bridge.cli import main\n"
         f"sys.exit(main({list(args)!r}))"], capture_output=True, text=True, env=env,
        timeout=60)


def test_without_zenoh_one_clear_line_and_exit_1() -> None:
    done = _cli("import sys; sys.modules['zenoh'] = None", "--out", "x")
    assert done.returncode == 1
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "pip install eclipse-zenoh" in lines[0], done.stderr
    assert lines[0].startswith("ln_zenoh: error:")


def test_bad_configuration_exit_2() -> None:
    fake = "import sys, types; sys.modules['zenoh'] = types.ModuleType('zenoh')"
    done = _cli(fake, "--in", "x")
    assert done.returncode == 2 and "remote" in done.stderr
    done = _cli(fake, "--out", "x,queued=5000")
    assert done.returncode == 2 and "buffers" in done.stderr
