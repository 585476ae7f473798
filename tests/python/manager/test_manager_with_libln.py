"""The contract between libln's own client code and ln_manager: a C client (driven through
the ctypes layer) registers, gets its segments from the manager, moves data through them,
follows a ring into its next generation, gets the manager's refusals as LN_E* errors with
the manager's text, and leaves nothing behind when destroyed; its HELLO names its host and
its subscribers' transport flags reach the manager."""

from __future__ import annotations

import ctypes
import re
from collections.abc import Callable

import pytest
from mgrproc import Manager, require_manager_library, segments, wait_for

require_manager_library()

import links_and_nodes as ln  # noqa: E402  (after the skip check)
from links_and_nodes import _adminlib  # noqa: E402
from links_and_nodes import _clientlib as C  # noqa: E402

SIZE = 16
HASH = 0x0123456789ABCDEF
MD = b"test/pair"
READ_TIMEOUT = 30.0  # seconds; an upper bound, the sample is always there already


class Client:
    def __init__(self, manager: Manager, name: str) -> None:
        opts = C.ClientOptions()
        C.ln_client_options_init(ctypes.byref(opts))
        opts.manager = f"127.0.0.1:{manager.port}".encode()
        handle = ctypes.c_void_p()
        C.ln_client_create(ctypes.byref(handle), name.encode(), ctypes.byref(opts))
        self.handle = handle
        self.name = C.ln_client_name(handle).decode()

    def port(self, fn: Callable[..., int], topic: str, buffers: int = 1,
             layout_hash: int = HASH, size: int = SIZE, flags: int = 0) -> ctypes.c_void_p:
        opts = C.PortOptions()
        C.ln_port_options_init(ctypes.byref(opts))
        opts.buffers = buffers
        opts.flags = flags
        port = ctypes.c_void_p()
        fn(self.handle, ctypes.byref(port), topic.encode(), MD, layout_hash, size,
           ctypes.byref(opts))
        return port

    def publish(self, topic: str, **kwargs: int) -> ctypes.c_void_p:
        return self.port(C.ln_publish, topic, **kwargs)

    def subscribe(self, topic: str, **kwargs: int) -> ctypes.c_void_p:
        return self.port(C.ln_subscribe, topic, **kwargs)

    def destroy(self) -> None:
        C.ln_client_destroy(self.handle)


def write(port: ctypes.c_void_p, payload: bytes) -> None:
    buf = ctypes.create_string_buffer(payload.ljust(SIZE, b"\0"), SIZE)
    C.ln_write(port, buf, SIZE, 0.0)


def read(port: ctypes.c_void_p) -> bytes:
    buf = ctypes.create_string_buffer(SIZE)
    info = C.SampleInfo()
    rc = C.ln_read(port, buf, SIZE, READ_TIMEOUT, ctypes.byref(info))
    assert rc == 0, C.last_error()
    return buf.raw.rstrip(b"\0")


def test_names_and_segments(manager: Manager) -> None:
    first, second = Client(manager, "cproc"), Client(manager, "cproc")
    assert (first.name, second.name) == ("cproc", "cproc-2")
    first.publish("pair")
    second.subscribe("pair")
    assert segments(manager.instance) == [f"ln.{manager.instance}.1.1"]
    first.destroy()
    second.destroy()
    wait_for(lambda: segments(manager.instance) == [], "the topic's segments to go")


def test_data_flows_and_follows_a_grown_ring(manager: Manager) -> None:
    client = Client(manager, "flow")
    pub = client.publish("pair")
    latest = client.subscribe("pair")
    write(pub, b"one")
    assert read(latest) == b"one"
    queued = client.subscribe("pair", buffers=8)  # the ring grows: generation 2
    assert segments(manager.instance) == [f"ln.{manager.instance}.1.{g}" for g in (1, 2)]
    for word in (b"two", b"three"):
        write(pub, word)
    assert [read(queued), read(queued)] == [b"two", b"three"]
    assert read(latest) == b"three"
    assert C.ln_outport_subscriber_count(pub) == 2
    assert C.ln_inport_publisher_count(latest) == 1
    client.destroy()
    wait_for(lambda: segments(manager.instance) == [], "the topic's segments to go")


def test_refusals_arrive_as_errors_with_the_managers_text(manager: Manager) -> None:
    client = Client(manager, "refused")
    client.publish("pair")
    with pytest.raises(ln.LnLayoutError):
        client.subscribe("pair", layout_hash=HASH + 1)
    assert "layout of md 'test/pair' (hash 0x0123456789abcdf0, 16 bytes) differs from the " \
           "topic's md 'test/pair' (hash 0x0123456789abcdef, 16 bytes)" in C.last_error()
    with pytest.raises(ln.LnLimitError):  # only the manager knows this limit
        client.subscribe("big", buffers=16, size=64 << 20)
    assert "the limit per topic is 1073741824" in C.last_error()
    client.destroy()


def test_hello_tells_the_host_id(manager: Manager) -> None:
    client = Client(manager, "hosted")
    host = ctypes.create_string_buffer(256)
    _adminlib.ln_host_id(host, len(host))
    assert host.value  # $LN_HOST_ID or hostname/boot_id, never empty
    manager.wait_log(rf"client hosted \(127\.0\.0\.1:\d+\): connected \(pid \d+, library "
                     rf"[0-9.]+, host {re.escape(host.value.decode())}\)")
    client.destroy()


def test_transport_flags_reach_the_manager(manager: Manager) -> None:
    client = Client(manager, "transport")
    client.publish("pair", flags=C.LN_PUBLISH_WAIT_FOR_SUBSCRIBERS)
    client.subscribe("pair", flags=C.LN_SUBSCRIBE_TCP)
    client.subscribe("pair", buffers=4, flags=C.LN_SUBSCRIBE_UDP)
    client.subscribe("pair")
    manager.wait_log(r"client transport \(\S+\): subscriber 'pair' -> port 4,")
    log = manager.log()
    ports = re.findall(r"client transport \(\S+\): (\w+) 'pair' -> port \d+, \S+"
                       r"(?: reader \d+)?(.*)", log)
    assert ports == [("publisher", ""), ("subscriber", ", transport tcp"),
                     ("subscriber", ", transport udp"), ("subscriber", "")]
    client.destroy()


@pytest.mark.parametrize("kind, flags, text", [
    ("subscribe", 0x300, "LN_SUBSCRIBE_UDP and LN_SUBSCRIBE_TCP together"),
    ("subscribe", 0x1, "LN_PUBLISH_WAIT_FOR_SUBSCRIBERS is a publisher flag"),
    ("publish", 0x200, "ln_publish: flags 0x200 hold LN_SUBSCRIBE_* bits"),
    ("publish", 0x101, "ln_publish: flags 0x101 hold LN_SUBSCRIBE_* bits"),
])
def test_flags_of_the_wrong_kind_are_refused_by_libln(manager: Manager, kind: str,
                                                       flags: int, text: str) -> None:
    client = Client(manager, "wrongflags")
    with pytest.raises(ln.LnInvalError):
        getattr(client, kind)("pair", flags=flags)
    assert text in C.last_error()
    assert segments(manager.instance) == []  # the manager never heard of it
    client.destroy()
