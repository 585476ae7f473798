"""The multi-host parts of a configuration: `network` sections (members by interface and
by subnet, exclusions, gateways), the hosts' data_port and IPv6 interfaces, and the
`topics` section with its first-match-wins lookup."""

from __future__ import annotations

from pathlib import Path

import pytest

from links_and_nodes.manager.config import ConfigError, load
from links_and_nodes.manager.config.model import (
    Interface,
    Member,
    TopicSetting,
    topic_transport,
)

from .helpers import cfg, load_files, loc, write

HOSTS = """
        hosts
        robot: eth0:192.168.0.2, wifi:10.0.0.2, data_port:6000
        gw: eth0:192.168.0.1, wifi:10.0.0.1, v6:fd00::1
        laptop: wifi:10.0.0.3, v6:fd00::3
        cam: eth0:192.168.0.9
        """  # indented like the tests' text, so that cfg() dedents both alike


def test_networks_by_interface_subnet_and_exclusion(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg(HOSTS + """
        network robot_net
            member_interfaces: robot/eth0, gw/eth0
            add member_interfaces: 192.168.0.0/24, !cam/eth0
            preferred_gateways: gw
        network wifi
            member_interfaces: 10.0.0.7/24, !192.168.0.0/16
            preferred_gateways: gw, robot
            add preferred_gateways: gw
        network v6
            member_interfaces: fd00::/64
        """)})
    main = tmp_path / "main.lnc"
    assert config.hosts["robot"].data_port == 6000
    assert config.hosts["gw"].interfaces["v6"] == "fd00::1"
    assert list(config.networks) == ["robot_net", "wifi", "v6"]
    robot_net = config.networks["robot_net"]
    assert robot_net.location == loc(main, 10, 1)
    assert robot_net.members == [Member(loc(main, 11, 24), host="robot", interface="eth0"),
                                 Member(loc(main, 11, 36), host="gw", interface="eth0"),
                                 Member(loc(main, 12, 28), subnet="192.168.0.0/24")]
    assert robot_net.excluded == [Member(loc(main, 12, 45), host="cam", interface="eth0")]
    assert robot_net.preferred_gateways == ["gw"]
    assert robot_net.interfaces == [Interface("robot", "eth0", "192.168.0.2"),
                                    Interface("gw", "eth0", "192.168.0.1")]
    assert robot_net.hosts() == ["robot", "gw"]
    wifi = config.networks["wifi"]
    assert [str(m) for m in wifi.members] == ["10.0.0.0/24"]  # host bits are dropped
    assert [str(m) for m in wifi.excluded] == ["192.168.0.0/16"]
    assert wifi.preferred_gateways == ["gw", "robot"]  # no repeats
    assert wifi.hosts() == ["robot", "gw", "laptop"]
    assert config.networks["v6"].interfaces == [Interface("gw", "v6", "fd00::1"),
                                                Interface("laptop", "v6", "fd00::3")]


def test_member_interfaces_without_add_replaces(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg(HOSTS + """
        network n
            member_interfaces: robot/eth0
            member_interfaces: [
                laptop/wifi
                gw/wifi, !gw/wifi
            ]
        """)})
    assert config.networks["n"].hosts() == ["laptop"]


def test_an_interface_may_be_in_several_networks(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg(HOSTS + """
        network a
            member_interfaces: gw/wifi, laptop/wifi
        network b
            member_interfaces: 10.0.0.0/8
        """)})
    shared = Interface("gw", "wifi", "10.0.0.1")
    assert shared in config.networks["a"].interfaces
    assert shared in config.networks["b"].interfaces


def test_networks_see_hosts_defined_later_and_in_includes(tmp_path: Path) -> None:
    config = load_files(tmp_path, {
        "main.lnc": cfg("""
            network lab
                member_interfaces: robot/eth0, 10.1.0.0/16
            include hosts.inc.lnc
            """),
        "hosts.inc.lnc": "hosts\nrobot: eth0:192.168.0.2\npc: lan:10.1.2.3\n",
    })
    assert config.networks["lab"].hosts() == ["robot", "pc"]


def test_duplicate_network_in_an_include_names_the_file(tmp_path: Path) -> None:
    main = write(tmp_path, {
        "main.lnc": cfg("""
            hosts
            robot: eth0:192.168.0.2
            include inc/net.lnc
            network lab
                member_interfaces: robot/eth0
            """),
        "inc/net.lnc": "network lab\n    member_interfaces: robot/eth0\n",
    })
    with pytest.raises(ConfigError) as err:
        load(main, env={})
    assert str(err.value) == (f"{main}:7:9: duplicate network 'lab' (first defined at "
                              "inc/net.lnc:1)")


def test_network_key_without_colon_gives_one_problem(tmp_path: Path) -> None:
    main = write(tmp_path, {"main.lnc": cfg("""
        hosts
        robot: eth0:192.168.0.2
        network lab
            member_interfaces robot/eth0
        """)})
    with pytest.raises(ConfigError) as err:
        load(main, env={})
    assert str(err.value) == f"{main}:7:5: missing ':' after key 'member_interfaces'"


def test_topics_first_match_wins_across_sections(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("""
        defines
        log: robot.log
        topics
        robot.log.camera: transport:udp
        %(log).*: transport:TCP      # evaluated, any case
        "robot:state": transport:tcp
        topics
        robot.*: transport:udp
        robot.log.?aw: transport:udp   # never wins: robot.log.* comes first
        cam[0-9]: transport:tcp
        """)})
    main = tmp_path / "main.lnc"
    assert config.topic_settings == [
        TopicSetting("robot.log.camera", "udp", loc(main, 7, 1)),
        TopicSetting("robot.log.*", "tcp", loc(main, 8, 1)),
        TopicSetting("robot:state", "tcp", loc(main, 9, 1)),
        TopicSetting("robot.*", "udp", loc(main, 11, 1)),
        TopicSetting("robot.log.?aw", "udp", loc(main, 12, 1)),
        TopicSetting("cam[0-9]", "tcp", loc(main, 13, 1)),
    ]
    assert topic_transport(config, "robot.log.camera") == "udp"
    assert topic_transport(config, "robot.log.raw") == "tcp"
    assert topic_transport(config, "robot.log.a.b") == "tcp"  # * crosses dots
    assert topic_transport(config, "robot:state") == "tcp"
    assert topic_transport(config, "robot.state") == "udp"
    assert topic_transport(config, "cam7") == "tcp"
    assert topic_transport(config, "Cam7") is None  # case-sensitive
    assert topic_transport(config, "other") is None


def test_no_topics_section_gives_no_transport(tmp_path: Path) -> None:
    config = load_files(tmp_path, {"main.lnc": cfg("")})
    assert config.topic_settings == [] and config.networks == {}
    assert topic_transport(config, "robot.state") is None
