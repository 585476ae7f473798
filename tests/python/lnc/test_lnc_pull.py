"""The pull settings of the `topics` section (docs/pull.md): defaults, first match per
setting, `pull:off`, the NDN names of topics, and file:line:col errors for bad values."""

from __future__ import annotations

from pathlib import Path

import pytest

from links_and_nodes.manager.config import ConfigError, load
from links_and_nodes.manager.config.model import PullSetting, topic_pull, topic_transport
from links_and_nodes.manager.config.pull_settings import pull_uri, uri_component

from .helpers import cfg, load_files, write


def test_pull_settings_defaults_and_first_match(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        topics
        arm.secret: pull:off
        arm.*: pull:NDN-UDP, pull_port:7000, pull_key:0a0B, pull_history:1
        arm.*: transport:tcp             # transport comes from here: the line above has none
        "cam:raw/./x": pull:ndn-udp, pull_prefix:/lab/r%2D1/, pull_freshness_ms:0
        "cam:*": pull:ndn-udp, pull_address:::1, pull_history:65536
        """)})
    assert topic_pull(config, "arm.secret") is None
    assert topic_transport(config, "arm.secret") == "tcp"
    assert topic_pull(config, "arm.state") == PullSetting("ndn-udp", port=7000,
                                                          key=b"\x0a\x0b", history=1)
    assert topic_transport(config, "arm.state") == "tcp"
    cam = topic_pull(config, "cam:raw/./x")
    assert cam == PullSetting("ndn-udp", prefix="/lab/r%2D1", freshness_ms=0)
    assert topic_pull(config, "cam:other") == PullSetting("ndn-udp", address="::1",
                                                          history=65536)
    assert topic_pull(config, "other") is None
    assert pull_uri(cam, "demo", "cam:raw/./x") == "/lab/r%2D1/cam%3Araw/..../x"
    default = topic_pull(config, "arm.state")
    assert default is not None and default.prefix is None
    assert pull_uri(default, "my lab", "arm.state") == "/ln/my%20lab/arm.state"
    assert PullSetting("ndn-udp") == PullSetting("ndn-udp", 6363, None, 64, 1000, b"",
                                                 "0.0.0.0")


def test_uri_components() -> None:
    assert uri_component("arm.state") == "arm.state"
    assert uri_component("a:b") == "a%3Ab"
    assert uri_component("..") == "....."
    assert uri_component("") == "..."
    assert pull_uri(PullSetting("ndn-udp", prefix="/"), "x", "a/b") == "/a/b"


@pytest.mark.parametrize(("line", "col", "message"), [
    ("a: pull:ndn-tcp", 9, "unknown pull transport 'ndn-tcp' (known: ndn-udp, off)"),
    ("a: pull_port:5", 14, "'pull_port' needs 'pull:ndn-udp' on the same line (topic "
                           "pattern 'a')"),
    ("a: pull:ndn-udp, pull_port:0", 28, "'pull_port' must be between 1 and 65535, got 0"),
    ("a: pull:ndn-udp, pull_port:65536", 28,
     "'pull_port' must be between 1 and 65535, got 65536"),
    ("a: pull:ndn-udp, pull_port:x", 28, "'pull_port' must be an integer, got 'x'"),
    ("a: pull:ndn-udp, pull_prefix:ln/x", 30,
     "'pull_prefix' must be an NDN name starting with '/', got 'ln/x'"),
    ("a: pull:ndn-udp, pull_prefix:/a//b", 30, "'pull_prefix' component '' of '/a//b' may "
                                               "only hold A-Z a-z 0-9 . _ ~ - and %XX escapes"),
    ("a: pull:ndn-udp, pull_prefix:/a b", 30, "'pull_prefix' component 'a b' of '/a b' may "
                                              "only hold A-Z a-z 0-9 . _ ~ - and %XX escapes"),
    ("a: pull:ndn-udp, pull_key:abc", 27,
     "'pull_key' must be the HMAC key as an even number of hex digits, got 'abc'"),
    ("a: pull:ndn-udp, pull_key:zz", 27,
     "'pull_key' must be the HMAC key as an even number of hex digits, got 'zz'"),
    ("a: pull:ndn-udp, pull_history:0", 31,
     "'pull_history' must be between 1 and 65536, got 0"),
    ("a: pull:ndn-udp, pull_history:65537", 31,
     "'pull_history' must be between 1 and 65536, got 65537"),
    ("a: pull:ndn-udp, pull_freshness_ms:-1", 36,
     "'pull_freshness_ms' must be between 0 and 4294967295, got -1"),
    ("a: pull:ndn-udp, pull_address:foo", 31,
     "'pull_address' must be an IPv4 or IPv6 address to bind, got 'foo'"),
    ("a: pull:off, pull_port:5", 24, "'pull_port' has no effect with 'pull:off'"),
    ("a: pull:ndn-udp, pull:off", 18, "topic setting 'pull' given twice"),
    ("a: pul:ndn-udp", 4, "unknown topic setting 'pul' (did you mean 'pull'?)"),
])
def test_bad_pull_values(tmp_path: Path, line: str, col: int, message: str) -> None:
    main = write(tmp_path, {"main.lnc": cfg("topics\n" + line + "\n")})
    with pytest.raises(ConfigError) as err:
        load(main, env={})
    assert str(err.value) == f"{main}:5:{col}: {message}"
