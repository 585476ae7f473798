"""REGISTER_SERVICE, UNREGISTER_SERVICE, FIND_SERVICE, SERVICE_CALLED and LIST_SERVICES
against a running ln_manager: round trips, every refusal with its code and text, one
provider per name, removal with the provider's connection, call counts, the listing (sorted,
cut at the frame limit), malformed bodies and the limit."""

from __future__ import annotations

import os
import re
import socket
import struct
from collections.abc import Callable
from pathlib import Path
from typing import Any

import lnwire
import pytest
from lnwire import frame, s
from mgrproc import Manager, require_manager_library

require_manager_library()

import links_and_nodes as ln  # noqa: E402  (after the skip check)
from links_and_nodes.manager.registry.core import Core, Session  # noqa: E402
from links_and_nodes.manager.registry.model import Registry  # noqa: E402
from links_and_nodes.manager.registry.services import Services  # noqa: E402
from links_and_nodes.tools import protocol as p  # noqa: E402

Start = Callable[..., Manager]
MD = "robot/move"
HASH = 0x0123456789ABCDEF
SIG = "robot/move_request|robot/move_response"
NOTFOUND = ln.LnNotfoundError.code


def register(client: lnwire.WireClient, name: str = "arm.move", md: str = MD,
             layout_hash: int = HASH, signature: str = SIG,
             **kwargs: object) -> lnwire.Reply:
    kwargs.setdefault("unix_path", f"/tmp/{name}.sock")
    return client.register_service(name, md, layout_hash, signature, **kwargs)


def test_register_and_find(manager: Manager) -> None:
    with manager.client("prov") as prov, manager.client("user") as user:
        reply = register(prov, group="arm", unix_path="/tmp/arm.sock", tcp_host="10.0.0.5",
                         tcp_port=4711, host_id="host-a")
        assert (reply.type, reply.fields) == (lnwire.OK, {"request_id": reply.request_id})
        info = user.find_service("arm.move", MD, HASH)
        assert info.type == lnwire.SERVICE_INFO
        assert (info.provider, info.host_id, info.unix_path, info.tcp_host, info.tcp_port,
                info.signature) == ("prov", "host-a", "/tmp/arm.sock", "10.0.0.5", 4711, SIG)
        # another md name with the same layout is fine, as for topics
        assert user.find_service("arm.move", "other/name", HASH).type == lnwire.SERVICE_INFO
        tcp_only = register(prov, "arm.stop", unix_path="", tcp_host="h", tcp_port=1)
        assert tcp_only.type == lnwire.OK
        stop = user.find_service("arm.stop", MD, HASH)
        assert (stop.unix_path, stop.host_id) == ("", "")
    manager.wait_log(r"client prov \(.*\): service 'arm.move' registered: md 'robot/move' "
                     r"\(hash 0x0123456789abcdef\), signature '[^']*', group 'arm', "
                     r"host 'host-a', unix /tmp/arm.sock, tcp 10.0.0.5:4711$")


@pytest.mark.parametrize("kwargs, code, text", [
    ({"name": ".hidden"}, "EINVAL", "service name '.hidden' must not start with '.'"),
    ({"name": "sp ace"}, "EINVAL", "may only contain A-Z a-z 0-9 _ . : / -"),
    ({"name": "s" * 256}, "EINVAL", "service name of 256 bytes, must be 1..255"),
    ({"md": "robot/1st"}, "EINVAL", "md name 'robot/1st'"),
    ({"signature": ""}, "EMD", "signature of 0 bytes"),
    ({"signature": "no_bar"}, "EMD", "must contain exactly one '|'"),
    ({"signature": "a|b|c"}, "EMD", "must contain exactly one '|'"),
    ({"unix_path": ""}, "EINVAL", "neither a unix path nor a tcp port given"),
    ({"unix_path": "relative.sock"}, "EINVAL", "is not an absolute path"),
    ({"unix_path": "/" + "p" * 107}, "EINVAL", "unix path of 108 bytes, at most 107"),
    ({"host_id": "h" * 256}, "EINVAL", "host id of 256 bytes, at most 255"),
])
def test_register_refusals(manager: Manager, kwargs: dict[str, object], code: str,
                           text: str) -> None:
    with manager.client("prov") as prov:
        reply = register(prov, **kwargs)
        assert reply.type == lnwire.ERROR
        assert reply.code == getattr(ln, f"Ln{code[1:].capitalize()}Error").code
        assert text in reply.text
        # refused, so nothing is registered, and the connection stays usable
        assert prov.find_service("arm.move", MD, HASH).code == NOTFOUND


def test_one_provider_per_name(manager: Manager) -> None:
    with manager.client("prov") as prov, manager.client("rival") as rival:
        assert register(prov).type == lnwire.OK
        reply = register(rival, unix_path="/tmp/rival.sock")
        assert (reply.type, reply.code) == (lnwire.ERROR, ln.LnExistError.code)
        assert re.fullmatch(r"service 'arm.move' is already provided by client 'prov' "
                            r"\(127\.0\.0\.1:\d+\)", reply.text), reply.text
        # the same provider replaces its own registration
        assert register(prov, unix_path="/tmp/new.sock", signature="x|y").type == lnwire.OK
        info = rival.find_service("arm.move", MD, HASH)
        assert (info.provider, info.unix_path, info.signature) == ("prov", "/tmp/new.sock",
                                                                   "x|y")
    manager.wait_log(r"service 'arm.move' re-registered")


def test_unregister(manager: Manager) -> None:
    with manager.client("prov") as prov, manager.client("other") as other:
        assert register(prov).type == lnwire.OK
        reply = other.unregister_service("arm.move")
        assert (reply.type, reply.code, reply.text) == (
            lnwire.ERROR, NOTFOUND, "client 'other' does not provide service 'arm.move'")
        assert prov.unregister_service("arm.move").type == lnwire.OK
        info = other.find_service("arm.move", MD, HASH)
        assert (info.code, info.text) == (NOTFOUND, "service 'arm.move' is not provided")
        assert prov.unregister_service("arm.move").code == NOTFOUND
        assert register(other).type == lnwire.OK  # the name is free again
    manager.wait_log(r"client prov \(.*\): service 'arm.move' unregistered \(0 calls, "
                     r"0 errors\)$")


def test_find_with_another_layout(manager: Manager) -> None:
    with manager.client("prov") as prov:
        assert register(prov).type == lnwire.OK
        reply = prov.find_service("arm.move", "robot/move_v2", 0xBAD)
        assert (reply.type, reply.code) == (lnwire.ERROR, ln.LnLayoutError.code)
        assert reply.text == ("service 'arm.move': layout of md 'robot/move_v2' (hash "
                              "0x0000000000000bad) differs from the service's md "
                              "'robot/move' (hash 0x0123456789abcdef)")


def test_provider_disconnect_removes_its_services(manager: Manager) -> None:
    user = manager.client("user")
    prov = manager.client("prov")
    assert register(prov, "s1").type == lnwire.OK
    assert register(prov, "s2").type == lnwire.OK
    assert register(user, "mine").type == lnwire.OK
    prov.close()
    manager.wait_log(r"client prov \(.*\): disconnected")
    for name in ("s1", "s2"):
        assert user.find_service(name, MD, HASH).code == NOTFOUND
    assert user.find_service("mine", MD, HASH).provider == "user"
    log = manager.log()
    for name in ("s1", "s2"):
        assert re.search(rf"service '{name}' of client prov \(.*\) removed: its client "
                         r"disconnected \(0 calls, 0 errors\)", log)
    # a new client may now provide the names
    with manager.client("prov") as again:
        assert register(again, "s1").type == lnwire.OK
    user.close()


def test_call_counts(start_manager: Start, instance: str) -> None:
    manager = start_manager(instance, "--log-level", "debug")
    with manager.client("prov") as prov, manager.client("other") as other:
        assert register(prov).type == lnwire.OK
        assert prov.service_called("arm.move", 3, 1).type == lnwire.OK
        assert prov.service_called("arm.move", (1 << 64) - 1, 2).type == lnwire.OK
        reply = other.service_called("arm.move", 99, 99)  # only the provider reports
        assert (reply.code, reply.text) == (
            NOTFOUND, "client 'other' does not provide service 'arm.move'")
        assert prov.service_called("nope", 1, 0).code == NOTFOUND
        assert prov.unregister_service("arm.move").type == lnwire.OK
    manager.wait_log(r"client prov \(.*\): service 'arm.move': 3 calls, 1 errors$")
    # counts are cumulative: the last report is what the manager keeps
    manager.wait_log(r"client prov \(.*\): service 'arm.move' unregistered "
                     r"\(18446744073709551615 calls, 2 errors\)$")


def test_list_services(manager: Manager) -> None:
    with (manager.client("prov") as prov, manager.client("tcpprov") as tcpprov,
          manager.client("user") as user):
        empty = user.list_services()
        assert (empty.type, empty.total, empty.count, empty.entries) == (
            lnwire.SERVICE_LIST, 0, 0, [])
        assert register(prov, "zeta", group="g1", host_id="host-a",
                        unix_path="/run/z.sock").type == lnwire.OK
        assert register(tcpprov, "alpha", md="other/md", layout_hash=7, unix_path="",
                        tcp_host="10.1.2.3", tcp_port=4711).type == lnwire.OK
        assert register(prov, "Mid.x", unix_path="/run/m.sock", tcp_host="h",
                        tcp_port=1).type == lnwire.OK
        assert prov.service_called("zeta", 41, 2).type == lnwire.OK
        assert prov.service_called("zeta", 42, 3).type == lnwire.OK
        assert tcpprov.service_called("alpha", (1 << 64) - 1, 1 << 40).type == lnwire.OK
        reply = user.list_services()
        assert (reply.type, reply.total, reply.count) == (lnwire.SERVICE_LIST, 3, 3)
        assert reply.entries == [  # by name: byte order, upper case first
            {"name": "Mid.x", "md_name": MD, "layout_hash": HASH, "provider": "prov",
             "group": "", "host_id": "", "unix_path": "/run/m.sock", "tcp_host": "h",
             "tcp_port": 1, "calls": 0, "errors": 0},
            {"name": "alpha", "md_name": "other/md", "layout_hash": 7, "provider": "tcpprov",
             "group": "", "host_id": "", "unix_path": "", "tcp_host": "10.1.2.3",
             "tcp_port": 4711, "calls": (1 << 64) - 1, "errors": 1 << 40},
            {"name": "zeta", "md_name": MD, "layout_hash": HASH, "provider": "prov",
             "group": "g1", "host_id": "host-a", "unix_path": "/run/z.sock", "tcp_host": "",
             "tcp_port": 0, "calls": 42, "errors": 3},
        ]
        # the provider may list too; what it unregisters or loses with its connection goes
        assert prov.unregister_service("Mid.x").type == lnwire.OK
        assert [e["name"] for e in prov.list_services().entries] == ["alpha", "zeta"]
        tcpprov.close()
        manager.wait_log(r"client tcpprov \(.*\): disconnected")
        reply = user.list_services()
        assert (reply.total, [e["name"] for e in reply.entries]) == (1, ["zeta"])


def _entry_size(entry: dict[str, object]) -> int:
    """Bytes of one SERVICE_LIST entry, from docs/protocol.md."""
    strs = ("name", "md_name", "provider", "group", "host_id", "unix_path", "tcp_host")
    return sum(2 + len(str(entry[k]).encode()) for k in strs) + 8 + 2 + 8 + 8


def test_list_services_is_cut_at_the_frame_limit(manager: Manager) -> None:
    count = 400  # about 3.2 kB each: more than 1 MiB together
    with manager.client("p" * 255) as prov, manager.client("user") as user:
        for i in reversed(range(count)):  # registration order is not the listing order
            reply = register(prov, f"{i:04d}" + "n" * 251, md="m" * 255, group="g" * 1024,
                             host_id="h" * 255, unix_path="/" + "u" * 106,
                             tcp_host="t" * 1024, tcp_port=1)
            assert reply.type == lnwire.OK, reply
        user.send(lnwire.LIST_SERVICES, struct.pack("<I", 77))
        length, type_ = struct.unpack("<IH", user._exactly(6))
        body = user._exactly(length - 2)
        reply = lnwire.parse(type_, body)
        assert (reply.type, reply.request_id, reply.total) == (lnwire.SERVICE_LIST, 77, count)
        assert 0 < reply.count < count
        assert length <= 1 << 20
        entry_size = _entry_size(reply.entries[0])
        assert entry_size > 3000
        assert length + entry_size > 1 << 20  # one more would not have fitted
        assert [e["name"][:4] for e in reply.entries] == [f"{i:04d}" for i in range(
            reply.count)]
        assert all(e["provider"] == prov.name and len(e["tcp_host"]) == 1024
                   for e in reply.entries)
        # the connection goes on as usual after the big frame
        assert user.find_service("0000" + "n" * 251, MD, HASH).type == lnwire.SERVICE_INFO


class _NoSegments:
    """Service requests never touch segments; this stands in for them."""


async def test_core_listing() -> None:
    registry = Registry(lambda size, slots: size * slots)
    core = Core("inst", registry, _NoSegments(), Services())  # type: ignore[arg-type]
    session = Session("127.0.0.1:9")
    core.hello(session, p.Hello(p.MAGIC, p.VERSION, 42, "prov", "0.1.0", ""))
    reply = await core.request(session, p.RegisterService(1, "b.svc", MD, HASH, SIG, "grp",
                                                          "hb", "/tmp/b.sock", "", 0))
    assert reply == p.Ok(1)
    await core.request(session, p.RegisterService(2, "a.svc", MD, 7, "x|y", "", "", "", "h", 9))
    assert await core.request(session, p.ServiceCalled(3, "b.svc", 12, 2)) == p.Ok(3)
    listing = core.services()
    assert [e["name"] for e in listing] == ["a.svc", "b.svc"]
    assert listing[1] == {"name": "b.svc", "md_name": MD, "layout_hash": HASH,
                          "signature": SIG, "group": "grp", "provider": "prov",
                          "provider_id": session.client.id,  # type: ignore[union-attr]
                          "host_id": "hb", "unix_path": "/tmp/b.sock", "tcp_host": "",
                          "tcp_port": 0, "calls": 12, "errors": 2}
    found = await core.request(session, p.FindService(4, "a.svc", "m/d", 7))
    assert found == p.ServiceInfo(4, "prov", "", "", "h", 9, "x|y")
    assert await core.request(session, p.ListServices(5)) == p.ServiceList(5, 2, (
        p.ServiceEntry("a.svc", MD, 7, "prov", "", "", "", "h", 9, 0, 0),
        p.ServiceEntry("b.svc", MD, HASH, "prov", "grp", "hb", "/tmp/b.sock", "", 0, 12, 2)))
    assert await core.disconnect(session) == 0
    assert core.services() == []
    other = Session("127.0.0.1:10")
    core.hello(other, p.Hello(p.MAGIC, p.VERSION, 43, "user", "0.1.0", ""))
    assert await core.request(other, p.ListServices(1)) == p.ServiceList(1, 0, ())


class _TwoHosts:
    """HostRings of a manager whose client "remote" runs on another host."""

    def __init__(self, core: Core) -> None:
        self.core = core
        self.remote_rings = object()

    def rings_for(self, client: Any) -> Any:
        return self.remote_rings if client.name == "remote" else self.core.local


async def test_only_local_providers_sockets_are_removed(tmp_path: Path) -> None:
    """A provider on another host named a socket path on its host; the same path here may
    be a live socket of a local provider (pids repeat across hosts): it must stay."""
    registry = Registry(lambda size, slots: size * slots)
    core = Core("inst", registry, _NoSegments(), Services(),  # type: ignore[arg-type]
                hosts=_TwoHosts)  # type: ignore[arg-type]
    paths = {name: str(tmp_path / f"svc.4242.{i}.sock") for i, name in enumerate(
        ("local", "remote"))}
    sockets = []
    for path in paths.values():
        sock = socket.socket(socket.AF_UNIX)
        sock.bind(path)
        sockets.append(sock)
    sessions = {}
    for i, name in enumerate(("local", "remote")):
        session = sessions[name] = Session(f"127.0.0.1:{10 + i}")
        core.hello(session, p.Hello(p.MAGIC, p.VERSION, 50 + i, name, "0.1.0", ""))
        reply = await core.request(session, p.RegisterService(
            1, f"{name}.svc", MD, HASH, SIG, "", "h", paths[name], "", 0))
        assert reply == p.Ok(1)
    await core.disconnect(sessions["remote"])
    await core.disconnect(sessions["local"])
    assert not os.path.exists(paths["local"])  # its provider is gone: removed
    assert os.path.exists(paths["remote"])  # another host's path: left alone
    for sock in sockets:
        sock.close()


def test_service_limit(start_manager: Start, instance: str) -> None:
    manager = start_manager(instance, "--service-limit", "2")
    with manager.client("a") as a, manager.client("b") as b:
        assert register(a, "s1").type == lnwire.OK
        assert register(b, "s2").type == lnwire.OK
        reply = register(a, "s3")
        assert (reply.code, reply.text) == (
            ln.LnLimitError.code,
            "service 's3': the manager already has 2 services, its limit is 2")
        assert register(a, "s1", group="again").type == lnwire.OK  # replacing is no new one
        assert b.unregister_service("s2").type == lnwire.OK
        assert register(a, "s3").type == lnwire.OK


def test_service_limit_option_is_checked(start_manager: Start, instance: str) -> None:
    manager = start_manager(instance, "--service-limit", "0", ready=False)
    assert manager.proc.wait(60) == 2
    assert "--service-limit must be at least 1" in manager.log()


_REG = lnwire.register_service_body(1, "x", MD, 1, "a|b", "", "/tmp/x")
BAD = [
    ("register-short", frame(lnwire.REGISTER_SERVICE, _REG[:-1]),
     f"REGISTER_SERVICE body too short: {len(_REG) - 1} bytes, ends inside tcp_port"),
    ("register-long", frame(lnwire.REGISTER_SERVICE, _REG + b"\0"),
     f"REGISTER_SERVICE body too long: {len(_REG) + 1} bytes, its fields take {len(_REG)}"),
    ("register-utf8", frame(lnwire.REGISTER_SERVICE, lnwire.register_service_body(
        1, "x", MD, 1, b"a|\xff", "", "/tmp/x")),
     r"REGISTER_SERVICE.signature: not valid UTF-8 \(byte 2\)"),
    ("unregister-long", frame(lnwire.UNREGISTER_SERVICE, struct.pack("<I", 1) + s("x") + b"!"),
     "UNREGISTER_SERVICE body too long: 8 bytes, its fields take 7"),
    ("find-short", frame(lnwire.FIND_SERVICE, lnwire.find_service_body(1, "x", MD, 1)[:-3]),
     "FIND_SERVICE body too short: .* bytes, ends inside layout_hash"),
    ("called-id-0", frame(lnwire.SERVICE_CALLED, lnwire.service_called_body(0, "x", 1, 0)),
     r"SERVICE_CALLED with request id 0 \(must be non-zero\)"),
    ("service-info", frame(lnwire.SERVICE_INFO, b""),
     "unexpected SERVICE_INFO frame from a client"),
    ("list-long", frame(lnwire.LIST_SERVICES, struct.pack("<II", 1, 0)),
     "LIST_SERVICES body too long: 8 bytes, its fields take 4"),
    ("list-id-0", frame(lnwire.LIST_SERVICES, struct.pack("<I", 0)),
     r"LIST_SERVICES with request id 0 \(must be non-zero\)"),
    ("service-list", frame(lnwire.SERVICE_LIST, struct.pack("<III", 1, 0, 0)),
     "unexpected SERVICE_LIST frame from a client"),
]


@pytest.mark.parametrize("data, reason", [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_malformed_bodies_close_only_that_connection(manager: Manager, data: bytes,
                                                     reason: str) -> None:
    with manager.client("calm") as calm:
        assert register(calm, "calm.svc").type == lnwire.OK
        evil = manager.client("evil")
        assert register(evil, "evil.svc").type == lnwire.OK
        evil.send_raw(data)
        evil.sock.shutdown(socket.SHUT_WR)
        assert evil.closed_by_peer()
        evil.close()
        manager.wait_log(rf"^.* client evil \(127\.0\.0\.1:\d+\): closing: {reason}$")
        manager.wait_log(r"client evil \(.*\): disconnected")
        assert calm.find_service("evil.svc", MD, HASH).code == NOTFOUND
        assert calm.find_service("calm.svc", MD, HASH).provider == "calm"
