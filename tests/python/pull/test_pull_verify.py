"""HMAC-SHA256 verification in libln_pull's consumer (ln_pull_set_verify_key): Data signed
by an independent producer (this folder's own codec, ndn_wire.py) and by the daemon with
its pull_key is taken; a tampered packet, an unsigned one (DigestSha256) and one signed
with another key are rejected, counted in stats.rejected and not delivered."""

from __future__ import annotations

import ctypes
import struct
from collections.abc import Iterator

import pytest

from links_and_nodes import _pull_lib as P

from . import ndn_wire as w
from .conftest import PullLab

ESIGNATURE = -7  # LN_NDN_ESIGNATURE
URI = "/t/verify"
KEY = bytes(range(1, 21))


def _set_verify_key() -> ctypes._CFuncPtr:
    f = P.lib.ln_pull_set_verify_key
    f.restype = ctypes.c_int
    f.argtypes = [ctypes.POINTER(P.Sub), ctypes.c_char_p, ctypes.c_size_t]
    return f


class Consumer:
    """One subscription of the C core, driven by hand: packets in, samples out."""

    def __init__(self, uri: str, key: bytes | None) -> None:
        self.sub = P.Sub()
        self.samples: list[tuple[int, bytes]] = []
        self._send = P.SendFn(lambda user, packet, size: None)
        self._data = P.DataFn(self._on_data)
        self._key = key  # the core keeps a pointer to these bytes
        o = P.Options()
        P.ln_pull_options_naive(ctypes.byref(o))
        assert (
            P.ln_pull_start(
                ctypes.byref(self.sub),
                uri.encode(),
                ctypes.byref(o),
                self._send,
                self._data,
                P.EventFn(),
                None,
                0,
                1,
            )
            == 0
        )
        assert (
            _set_verify_key()(ctypes.byref(self.sub), key, len(key) if key is not None else 0) == 0
        )

    def _on_data(
        self, user: int, seq: int, payload: ctypes.Array, size: int, publish_us: int
    ) -> None:
        self.samples.append((seq, ctypes.string_at(payload, size)))

    def receive(self, packet: bytes) -> int:
        return P.ln_pull_receive(ctypes.byref(self.sub), packet, len(packet), 5)


def sync_reply(uri: str, seq: int, key: bytes) -> bytes:
    name = w.name_value(uri, seq, ("sync",))
    # name_value puts extra components before the seq: /t/verify/sync/seq=<seq>
    content = w.pull_content(
        seq, publish_us=1_700_000_000_000_000, period_us=20_000, payload=struct.pack("<Q", seq)
    )
    return w.data(name, content, key=key)


def tampered(packet: bytes) -> bytes:
    """The same packet with one byte of the sample's payload changed."""
    i = packet.index(struct.pack("<Q", 42)[:1] + b"\x00" * 7)
    return packet[:i] + b"\x2b" + packet[i + 1 :]


@pytest.fixture
def consumer() -> Iterator[Consumer]:
    yield Consumer(URI, KEY)


def test_signed_by_an_independent_producer_is_taken(consumer: Consumer) -> None:
    assert consumer.receive(sync_reply(URI, 42, KEY)) == 1
    assert consumer.samples == [(42, struct.pack("<Q", 42))]
    assert (consumer.sub.stats.data, consumer.sub.stats.rejected) == (1, 0)


@pytest.mark.parametrize("how", ["tampered", "unsigned", "other key"])
def test_a_packet_that_does_not_verify_is_rejected(consumer: Consumer, how: str) -> None:
    packet = {
        "tampered": tampered(sync_reply(URI, 42, KEY)),
        "unsigned": sync_reply(URI, 42, b""),
        "other key": sync_reply(URI, 42, b"another key"),
    }[how]
    assert consumer.receive(packet) == ESIGNATURE
    assert consumer.samples == []
    stats = consumer.sub.stats
    assert (stats.rejected, stats.bad, stats.data) == (1, 0, 0)
    assert consumer.receive(sync_reply(URI, 43, KEY)) == 1  # the next good one still counts
    assert consumer.samples == [(43, struct.pack("<Q", 43))]


def test_without_a_key_both_kinds_are_taken() -> None:
    plain = Consumer(URI, None)
    assert plain.receive(sync_reply(URI, 42, b"")) == 1
    assert plain.receive(sync_reply("/t/other", 50, KEY)) == 0  # another name: not ours
    assert plain.sub.stats.rejected == 0 and len(plain.samples) == 1


def test_bad_arguments() -> None:
    f = _set_verify_key()
    assert f(None, KEY, len(KEY)) == -8  # LN_NDN_EINVAL
    assert f(ctypes.byref(P.Sub()), None, 3) == -8


def test_daemon_signed_data_verifies(pulllab: PullLab) -> None:
    topic = "arm.state"
    pulllab.serve(extra=f", pull_key:{KEY.hex()}")
    pulllab.publisher(topic, 2000)
    pulllab.served(topic)
    uri = pulllab.uri(topic)
    sync = w.interest(
        w.name_value(uri, None, ("sync",)), nonce=77, can_be_prefix=True, must_be_fresh=True
    )
    reply = pulllab.ask(sync)
    assert reply is not None and w.decode_data(reply).signature_type == 4
    good = Consumer(uri, KEY)
    assert good.receive(reply) == 1 and len(good.samples) == 1
    wrong = Consumer(uri, b"not the daemon's key")
    assert wrong.receive(reply) == ESIGNATURE and wrong.samples == []
    assert wrong.sub.stats.rejected == 1
    d = w.decode_data(reply)
    flipped = reply.replace(d.content, bytes([d.content[0] ^ 1]) + d.content[1:], 1)
    again = Consumer(uri, KEY)
    assert again.receive(flipped) == ESIGNATURE and again.samples == []
