"""The service registry's decisions without sockets: the checks of REGISTER_SERVICE in the
documented order, one provider per name, replacing, the limit, lookups, call counts,
removal with the provider and which unix paths are still offered."""

from __future__ import annotations

from typing import Any

import pytest

from links_and_nodes.manager.registry.model import Registry, RequestError
from links_and_nodes.manager.registry.services import ServiceOffer, Services

HASH = 0x0123456789ABCDEF
SIG = "robot/move_request|robot/move_response"


def offer(name: str = "arm.move", md: str = "robot/move", layout_hash: int = HASH,
          signature: str = SIG, group: str = "arm", host_id: str = "host-a",
          unix_path: str = "/run/ln/arm.move", tcp_host: str = "",
          tcp_port: int = 0) -> ServiceOffer:
    return ServiceOffer(name, md, layout_hash, signature, group, host_id, unix_path, tcp_host,
                        tcp_port)


class World:
    def __init__(self, limit: int = 4096) -> None:
        self.registry = Registry(lambda size, slots: size * slots)
        self.a = self.registry.add_client("prov", 1, "127.0.0.1:1", "0.1.0")
        self.b = self.registry.add_client("other", 2, "127.0.0.1:2", "0.1.0")
        self.services = Services(limit)

    def refused(self, code: str, client: Any = None, **kwargs: Any) -> str:
        with pytest.raises(RequestError) as info:
            self.services.register(client or self.a, offer(**kwargs))
        assert info.value.code == code, info.value.text
        return info.value.text


@pytest.mark.parametrize("kwargs, code, text", [
    ({"name": ""}, "EINVAL", "service name of 0 bytes, must be 1..255"),
    ({"name": ".x"}, "EINVAL", "service name '.x' must not start with '.'"),
    ({"name": "a b"}, "EINVAL", "service name 'a b' may only contain A-Z a-z 0-9 _ . : / -"),
    ({"name": "s" * 256}, "EINVAL", "service name of 256 bytes, must be 1..255"),
    ({"md": "robot//x"}, "EINVAL", "md name 'robot//x': component ''"),
    ({"signature": ""}, "EMD", "signature of 0 bytes, must be 1..1024"),
    ({"signature": "a|" + "b" * 1023}, "EMD", "signature of 1025 bytes, must be 1..1024"),
    ({"signature": "req"}, "EMD", "must contain exactly one '|'"),
    ({"signature": "a|b|c"}, "EMD", "must contain exactly one '|'"),
    ({"host_id": "h" * 256}, "EINVAL", "service 'arm.move': host id of 256 bytes, at most 255"),
    ({"host_id": "ä" * 128}, "EINVAL", "host id of 256 bytes"),
    ({"unix_path": "", "tcp_port": 0}, "EINVAL", "neither a unix path nor a tcp port"),
    ({"unix_path": "rel/path"}, "EINVAL", "unix path 'rel/path' is not an absolute path"),
    ({"unix_path": "/" + "p" * 107}, "EINVAL", "unix path of 108 bytes, at most 107"),
    ({"unix_path": "/a\0b"}, "EINVAL", "is not an absolute path"),
])
def test_register_checks(kwargs: dict[str, Any], code: str, text: str) -> None:
    world = World()
    assert text in world.refused(code, **kwargs)
    assert world.services.by_name == {}


def test_checks_come_in_the_documented_order() -> None:
    world = World()
    world.services.register(world.b, offer())
    bad = {"md": "1x", "signature": "", "unix_path": "", "tcp_port": 0}
    assert "service name" in world.refused("EINVAL", name=".x", **bad)
    assert "md name" in world.refused("EINVAL", **bad)
    world.refused("EMD", **{**bad, "md": "m"})
    assert "host id" in world.refused("EINVAL", host_id="h" * 256, unix_path="", tcp_port=0)
    assert "neither" in world.refused("EINVAL", unix_path="", tcp_port=0)
    world.refused("EEXIST")


def test_addresses_accepted() -> None:
    world = World()
    world.services.register(world.a, offer(name="tcp", unix_path="", tcp_host="h",
                                           tcp_port=7))
    world.services.register(world.a, offer(name="unix", unix_path="/" + "p" * 106))
    world.services.register(world.a, offer(name="both", tcp_host="h", tcp_port=7))
    world.services.register(world.a, offer(name="no_host_id", host_id=""))
    world.services.register(world.a, offer(name="long_host_id", host_id="h" * 255))
    assert sorted(world.services.by_name) == ["both", "long_host_id", "no_host_id", "tcp",
                                              "unix"]


def test_one_provider_per_name_and_replacing() -> None:
    world = World()
    first, old = world.services.register(world.a, offer())
    assert old is None
    text = world.refused("EEXIST", client=world.b, unix_path="/other")
    assert text == "service 'arm.move' is already provided by client 'prov' (127.0.0.1:1)"
    world.services.called(world.a, "arm.move", 5, 1)
    second, old = world.services.register(world.a, offer(unix_path="/new", group="g2"))
    assert old is first and world.services.by_name["arm.move"] is second
    assert (second.offer.unix_path, second.offer.group, second.calls) == ("/new", "g2", 0)


def test_unregister_only_own() -> None:
    world = World()
    world.services.register(world.a, offer())
    with pytest.raises(RequestError) as info:
        world.services.unregister(world.b, "arm.move")
    assert (info.value.code, info.value.text) == (
        "ENOTFOUND", "client 'other' does not provide service 'arm.move'")
    assert world.services.unregister(world.a, "arm.move").provider is world.a
    with pytest.raises(RequestError) as info:
        world.services.unregister(world.a, "arm.move")
    assert info.value.code == "ENOTFOUND"


def test_find() -> None:
    world = World()
    world.services.register(world.a, offer())
    assert world.services.find("arm.move", "other/md", HASH).provider is world.a
    with pytest.raises(RequestError) as info:
        world.services.find("arm.move", "robot/move_v2", 0xABC)
    assert (info.value.code, info.value.text) == (
        "ELAYOUT", "service 'arm.move': layout of md 'robot/move_v2' (hash "
        "0x0000000000000abc) differs from the service's md 'robot/move' (hash "
        "0x0123456789abcdef)")
    with pytest.raises(RequestError) as info:
        world.services.find("nope", "robot/move", HASH)
    assert (info.value.code, info.value.text) == ("ENOTFOUND",
                                                  "service 'nope' is not provided")


def test_call_counts_only_from_the_provider() -> None:
    world = World()
    world.services.register(world.a, offer())
    world.services.called(world.a, "arm.move", 3, 0)
    world.services.called(world.a, "arm.move", 10, 2)  # cumulative: replaces
    with pytest.raises(RequestError) as info:
        world.services.called(world.b, "arm.move", 99, 99)
    assert info.value.code == "ENOTFOUND"
    [entry] = world.services.listing()
    assert entry == {"name": "arm.move", "md_name": "robot/move", "layout_hash": HASH,
                     "signature": SIG, "group": "arm", "provider": "prov",
                     "provider_id": world.a.id, "host_id": "host-a",
                     "unix_path": "/run/ln/arm.move",
                     "tcp_host": "", "tcp_port": 0, "calls": 10, "errors": 2}


def test_limit() -> None:
    world = World(limit=2)
    world.services.register(world.a, offer(name="s1"))
    world.services.register(world.b, offer(name="s2"))
    assert world.refused("ELIMIT", name="s3") == (
        "service 's3': the manager already has 2 services, its limit is 2")
    world.services.register(world.a, offer(name="s1", group="again"))  # replacing is fine
    world.services.unregister(world.b, "s2")
    world.services.register(world.a, offer(name="s3"))
    with pytest.raises(ValueError):
        Services(0)


def test_remove_client() -> None:
    world = World()
    world.services.register(world.a, offer(name="s1"))
    world.services.register(world.b, offer(name="s2"))
    world.services.register(world.a, offer(name="s3"))
    gone = world.services.remove_client(world.a)
    assert sorted(s.name for s in gone) == ["s1", "s3"]
    assert [e["name"] for e in world.services.listing()] == ["s2"]
    assert world.services.remove_client(world.a) == []


def test_sorted_by_name() -> None:
    world = World()
    for name in ("b", "a.x", "B", "a", "a_"):
        world.services.register(world.a, offer(name=name))
    assert [s.name for s in world.services.sorted()] == ["B", "a", "a.x", "a_", "b"]
    assert [e["name"] for e in world.services.listing()] == ["B", "a", "a.x", "a_", "b"]


def test_unix_path_in_use() -> None:
    world = World()
    world.services.register(world.a, offer(name="s1", unix_path="/run/x.sock"))
    world.services.register(world.b, offer(name="s2", unix_path="/run/x.sock"))
    assert world.services.unix_path_in_use("/run/x.sock")
    assert not world.services.unix_path_in_use("/run/y.sock")
    world.services.unregister(world.a, "s1")
    assert world.services.unix_path_in_use("/run/x.sock")
    world.services.remove_client(world.b)
    assert not world.services.unix_path_in_use("/run/x.sock")
