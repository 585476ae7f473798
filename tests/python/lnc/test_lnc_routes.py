"""What the `hosts` and `network` sections mean for traffic between hosts (routes.py):
direct links, routes over gateways, the preferred-gateway and name tie-breaks, exclusions,
NoRoute texts; and the daemon addresses the manager derives from them (daemons.py)."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from links_and_nodes.manager.config import Config, model
from links_and_nodes.manager.network.routes import Hop, NoRoute, host_address, host_of, route
from links_and_nodes.manager.processes.daemons import DaemonPool

from .helpers import cfg, load_files

# robot_net: robot, gw1, gw2 (and cam, excluded); wifi: gw1, gw2, laptop
TWO_SUBNETS = """
    hosts
    robot: eth0:192.168.0.2, wifi:10.0.0.2
    gw1: eth0:192.168.0.11, wifi:10.0.0.11
    gw2: eth0:192.168.0.12, wifi:10.0.0.12
    laptop: wifi:10.0.0.3
    cam: eth0:192.168.0.9
    network robot_net
        member_interfaces: 192.168.0.0/24, !cam/eth0
    network wifi
        member_interfaces: 10.0.0.0/24, !robot/wifi
    """


def config_of(tmp_path: Path, body: str) -> Config:
    return load_files(tmp_path, {"main.lnc": cfg(body)})


def test_without_networks_every_host_is_direct(tmp_path: Path) -> None:
    config = config_of(tmp_path, """
        hosts
        robot: eth0:192.168.0.2, wifi:10.0.0.2
        bare: daemon_port:5000
        node_map
        arm: robot
        """)
    assert route(config, "laptop", "robot") == [Hop("laptop", "robot", "192.168.0.2")]
    assert host_address(config, "laptop", "robot") == "192.168.0.2"  # the first interface
    assert host_address(config, "robot", "bare") == "bare"  # no interfaces: its name
    assert host_address(config, "robot", "unlisted") == "unlisted"
    assert route(config, "robot", "robot") == []
    assert host_address(config, "robot", "robot") == "127.0.0.1"
    assert host_of(config, "arm", "mgr") == "robot"
    assert host_of(config, "localhost", "mgr") == "mgr"
    assert host_of(config, "camera-pc", "mgr") == "camera-pc"


def test_a_shared_network_is_direct_at_the_interface_in_it(tmp_path: Path) -> None:
    config = config_of(tmp_path, """
        hosts
        robot: eth0:192.168.0.2, wifi:10.0.0.2
        laptop: wifi:10.0.0.3
        network wifi
            member_interfaces: laptop/wifi, robot/wifi
        """)
    assert route(config, "laptop", "robot") == [Hop("laptop", "robot", "10.0.0.2")]
    assert host_address(config, "robot", "laptop") == "10.0.0.3"


def test_several_common_networks_use_the_first_in_file_order(tmp_path: Path) -> None:
    config = config_of(tmp_path, """
        hosts
        a: eth0:192.168.0.1, wifi:10.0.0.1
        b: eth0:192.168.0.2, wifi:10.0.0.2
        network wifi
            member_interfaces: 10.0.0.0/24
        network wired
            member_interfaces: 192.168.0.0/24
        """)
    assert host_address(config, "a", "b") == "10.0.0.2"
    assert host_address(config, "b", "a") == "10.0.0.1"


def test_via_one_gateway_and_the_name_tie_break(tmp_path: Path) -> None:
    config = config_of(tmp_path, TWO_SUBNETS)
    assert host_address(config, "laptop", "robot") is None
    # gw1 and gw2 are equal; without preferences the smaller name wins
    assert route(config, "laptop", "robot") == [Hop("laptop", "gw1", "10.0.0.11"),
                                                Hop("gw1", "robot", "192.168.0.2")]
    assert route(config, "robot", "laptop") == [Hop("robot", "gw1", "192.168.0.11"),
                                                Hop("gw1", "laptop", "10.0.0.3")]
    assert route(config, "gw2", "robot") == [Hop("gw2", "robot", "192.168.0.2")]


def test_preferred_gateways_win_among_equal_routes(tmp_path: Path) -> None:
    config = config_of(tmp_path, TWO_SUBNETS + """
        preferred_gateways: gw2
    """)  # of network wifi
    assert config.networks["wifi"].preferred_gateways == ["gw2"]
    assert route(config, "laptop", "robot") == [Hop("laptop", "gw2", "10.0.0.12"),
                                                Hop("gw2", "robot", "192.168.0.2")]
    assert route(config, "robot", "laptop") == [Hop("robot", "gw2", "192.168.0.12"),
                                                Hop("gw2", "laptop", "10.0.0.3")]


def test_a_preference_of_an_uninvolved_network_does_not_count(tmp_path: Path) -> None:
    config = config_of(tmp_path, TWO_SUBNETS + """
    network service
        member_interfaces: gw2/wifi, cam/eth0
        preferred_gateways: gw2
    """)
    assert [h.dst for h in route(config, "laptop", "robot")] == ["gw1", "robot"]
    assert [h.dst for h in route(config, "laptop", "cam")] == ["gw2", "cam"]


def test_a_preferred_gateway_beats_the_name_order(tmp_path: Path) -> None:
    config = config_of(tmp_path, """
        hosts
        a: n1:10.1.0.1
        b: n1:10.1.0.2, n2:10.2.0.2
        c: n1:10.1.0.3, n3:10.3.0.3
        d: n3:10.3.0.4, n2:10.2.0.4
        network one
            member_interfaces: 10.1.0.0/16
        network two
            member_interfaces: 10.2.0.0/16
        network three
            member_interfaces: 10.3.0.0/16
            preferred_gateways: c
        """)
    # a -> b -> d and a -> c -> d are both two hops: c is preferred (by network three)
    assert [h.dst for h in route(config, "a", "d")] == ["c", "d"]
    assert [h.dst for h in route(config, "d", "a")] == ["c", "a"]


def test_fewer_hops_beat_preferred_gateways(tmp_path: Path) -> None:
    config = config_of(tmp_path, """
        hosts
        a: n1:10.1.0.1
        x: n1:10.1.0.2, n2:10.2.0.2
        p: n1:10.1.0.3, n3:10.3.0.3
        q: n3:10.3.0.4, n2:10.2.0.4
        d: n2:10.2.0.5
        network one
            member_interfaces: 10.1.0.0/16
            preferred_gateways: p
        network two
            member_interfaces: 10.2.0.0/16
            preferred_gateways: q
        network three
            member_interfaces: 10.3.0.0/16
            preferred_gateways: p, q
        """)
    assert [h.dst for h in route(config, "a", "d")] == ["x", "d"]


def test_two_gateways_in_a_row(tmp_path: Path) -> None:
    config = config_of(tmp_path, """
        hosts
        a: n1:10.1.0.1
        b: n1:10.1.0.2, n2:10.2.0.2
        c: n2:10.2.0.3, n3:10.3.0.3
        d: n3:10.3.0.4
        network one
            member_interfaces: 10.1.0.0/16
        network two
            member_interfaces: 10.2.0.0/16
        network three
            member_interfaces: 10.3.0.0/16
        """)
    assert route(config, "a", "d") == [Hop("a", "b", "10.1.0.2"), Hop("b", "c", "10.2.0.3"),
                                       Hop("c", "d", "10.3.0.4")]
    assert route(config, "d", "a") == [Hop("d", "c", "10.3.0.3"), Hop("c", "b", "10.2.0.2"),
                                       Hop("b", "a", "10.1.0.1")]


def test_an_exclusion_removes_a_link(tmp_path: Path) -> None:
    body = """
        hosts
        robot: wifi:10.0.0.2, eth0:192.168.0.2
        gw: wifi:10.0.0.1, eth0:192.168.0.1
        laptop: wifi:10.0.0.3
        network wired
            member_interfaces: 192.168.0.0/24
        network wifi
            member_interfaces: 10.0.0.0/24{exclude}
        """
    config = config_of(tmp_path, body.format(exclude=""))
    assert route(config, "laptop", "robot") == [Hop("laptop", "robot", "10.0.0.2")]
    config = config_of(tmp_path, body.format(exclude=", !robot/wifi"))
    assert route(config, "laptop", "robot") == [Hop("laptop", "gw", "10.0.0.1"),
                                                Hop("gw", "robot", "192.168.0.2")]


def test_no_route_names_the_hosts_and_their_networks(tmp_path: Path) -> None:
    config = config_of(tmp_path, """
        hosts
        a: n1:10.1.0.1, n2:10.2.0.1
        b: n1:10.1.0.2
        c: n3:10.3.0.3
        lonely: eth0:192.168.9.9
        node_map
        arm: ghost
        network one
            member_interfaces: 10.1.0.0/16
        network two
            member_interfaces: 10.2.0.0/16, 10.9.0.0/16
        network three
            member_interfaces: c/n3
        """)
    with pytest.raises(NoRoute) as err:
        route(config, "a", "c")
    assert str(err.value) == ("no route from host 'a' to host 'c': 'a' is in networks one, "
                              "two; 'c' is in network three; no chain of hosts with common "
                              "networks connects them")
    with pytest.raises(NoRoute) as err:
        route(config, "lonely", "b")
    assert str(err.value) == ("no route from host 'lonely' to host 'b': 'lonely' is in no "
                              "network; 'b' is in network one")
    with pytest.raises(NoRoute) as err:
        route(config, "b", host_of(config, "arm", "mgr"))
    assert str(err.value) == ("no route from host 'b' to host 'ghost': 'b' is in network one; "
                              "'ghost' has no entry in 'hosts', so it is in no network")
    assert host_address(config, "b", "ghost") is None
    assert host_address(config, "a", "c") is None


def pool(config: Config, tmp_path: Path) -> DaemonPool:
    return DaemonPool(config, "inst", key_file=tmp_path / "key", start_local=False,
                      local_host="mgr")


def test_daemon_addresses_without_networks(tmp_path: Path,
                                           monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("LN_ARBITER_PORT", raising=False)
    config = config_of(tmp_path, """
        hosts
        robot: eth0:192.168.0.2, wifi:10.0.0.2, daemon_port:5000
        mgr: eth0:192.168.0.1, daemon_port:5001
        node_map
        arm: robot
        here: mgr
        """)
    daemons = pool(config, tmp_path)
    assert daemons.address("arm") == ("192.168.0.2", 5000)
    assert daemons.address("robot") == ("192.168.0.2", 5000)
    assert daemons.address("camera-pc") == ("camera-pc", 54376)
    assert daemons.address("localhost") == ("127.0.0.1", 5001)
    assert daemons.address("here") == ("127.0.0.1", 5001)
    assert daemons.is_local("here") and daemons.is_local("localhost")
    assert not daemons.is_local("arm")


def test_daemon_addresses_follow_the_shared_network(tmp_path: Path) -> None:
    config = config_of(tmp_path, """
        hosts
        robot: eth0:192.168.0.2, wifi:10.0.0.2
        mgr: wifi:10.0.0.1
        cam: eth0:192.168.0.9
        network wifi
            member_interfaces: 10.0.0.0/24
        network wired
            member_interfaces: 192.168.0.0/24
        """)
    daemons = pool(config, tmp_path)
    assert daemons.address("robot")[0] == "10.0.0.2"  # not its first interface
    # no network in common with the manager's host: the first interface, as before
    assert daemons.address("cam")[0] == "192.168.0.9"
    assert daemons.address("localhost")[0] == "127.0.0.1"


# ---------------------------------------------------------------- against brute force

HOST_NAMES = ["a", "b", "c", "d", "e", "f"]
LOC = model.Location("<test>", 1, 1)


@st.composite
def topologies(draw: st.DrawFn) -> Config:
    """Up to 6 hosts with one interface per network they are in; up to 4 networks, each
    with random preferred gateways."""
    count = draw(st.integers(1, 4))
    hosts = {h: model.Host(h, LOC) for h in HOST_NAMES}
    networks = {}
    for n in range(count):
        members = draw(st.lists(st.sampled_from(HOST_NAMES), unique=True, max_size=4))
        net = model.Network(f"n{n}", LOC, preferred_gateways=draw(
            st.lists(st.sampled_from(HOST_NAMES), unique=True, max_size=2)))
        for h in members:
            address = f"10.{n}.0.{HOST_NAMES.index(h) + 1}"
            hosts[h].interfaces[f"if{n}"] = address
            net.interfaces.append(model.Interface(h, f"if{n}", address))
        networks[net.name] = net
    return Config(files=[], instance=model.Instance("t", ":1", LOC), hosts=hosts,
                  networks=networks)


def brute_force(config: Config, src: str, dst: str) -> list[str] | None:
    """The best path by enumerating every simple path."""
    nets = [set(n.hosts()) for n in config.networks.values()]

    def linked(x: str, y: str) -> bool:
        return any(x in n and y in n for n in nets)

    def penalty(path: tuple[str, ...]) -> int:
        count = 0
        for before, gw, after in zip(path, path[1:], path[2:], strict=False):
            count += not any(gw in net.preferred_gateways and gw in hosts
                             and (before in hosts or after in hosts)
                             for net, hosts in zip(config.networks.values(), nets, strict=True))
        return count

    paths = []

    def walk(path: tuple[str, ...]) -> None:
        if path[-1] == dst:
            paths.append(path)
            return
        for h in HOST_NAMES:
            if h not in path and linked(path[-1], h):
                walk((*path, h))

    walk((src,))
    if not paths:
        return None
    return list(min(paths, key=lambda p: (len(p), penalty(p), p)))


@settings(max_examples=300, deadline=None)
@given(topologies(), st.sampled_from(HOST_NAMES), st.sampled_from(HOST_NAMES))
def test_routes_are_the_best_simple_paths(config: Config, src: str, dst: str) -> None:
    if src == dst:
        assert route(config, src, dst) == []
        return
    expected = brute_force(config, src, dst)
    if expected is None:
        with pytest.raises(NoRoute):
            route(config, src, dst)
        return
    hops = route(config, src, dst)
    assert [src] + [h.dst for h in hops] == expected
    for hop in hops:
        assert hop.address in config.hosts[hop.dst].interfaces.values()
        assert any(hop.src in n.hosts() and hop.dst in n.hosts() and any(
            i.host == hop.dst and i.address == hop.address for i in n.interfaces)
            for n in config.networks.values())
    assert (host_address(config, src, dst) is not None) == (len(hops) == 1)
