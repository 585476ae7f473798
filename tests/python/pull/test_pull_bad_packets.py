"""Bad packets at a pull producer's port (docs/pull.md): random bytes, truncated TLVs, huge
VAR-NUMBERs, Data instead of Interests, Interests for names nobody serves, and a flood of
10,000 garbage datagrams are dropped and counted as bad / unknown / other in the network
view; the daemon, a normal subscriber of another topic and the pull consumer keep working."""

from __future__ import annotations

import random

from polling import wait_for

import links_and_nodes as ln

from . import ndn_wire as w
from .conftest import PullLab

TOPIC = "arm.state"
OTHER = "other.state"


def garbage(rng: random.Random, n: int) -> bytes:
    """Random bytes that do not start like a packet (Interest, Data, LpPacket)."""
    first = rng.choice([b for b in range(256) if b not in (0x05, 0x06, 0x64)])
    return bytes([first]) + rng.randbytes(n - 1)


def bad_packets(uri: str) -> tuple[list[bytes], list[bytes], list[bytes]]:
    """(undecodable, unknown names, not Interests)"""
    rng = random.Random(14)
    good = w.interest(w.name_value(uri, 1), nonce=5)
    undecodable = [garbage(rng, n) for n in (1, 2, 7, 100, 1400)]
    undecodable += [good[:k] for k in (1, 2, 3, len(good) // 2, len(good) - 1)]  # truncated
    undecodable += [b"\x05\xff" + b"\xff" * 8 + b"\x07\x00",  # length 2^64-1
                    b"\x05\xfe\xff\xff\xff\xff",  # a 4-byte length, nothing behind it
                    b"\x05\x00",  # an Interest without a Name
                    w.tlv(w.INTEREST, w.tlv(w.NAME, b"\x08\xfd\xff")),  # component cut off
                    w.tlv(w.INTEREST, w.tlv(w.NAME, w.tlv(w.GENERIC, b"a")) + w.tlv(0x0D)),
                    w.tlv(w.LP_PACKET, b"\x51\x01")]  # an LpPacket cut inside a header
    unknown = [w.interest(w.name_value("/nobody/serves/this", 1), nonce=6),
               w.interest(w.name_value(uri + "x", None, ("sync",)), nonce=7,
                          can_be_prefix=True, must_be_fresh=True)]
    data = [w.data(w.name_value(uri, 1), b"x"), w.data(w.name_value("/a/b"), b"", key=b"k")]
    return undecodable, unknown, data


def test_bad_packets_counted_and_nothing_else_disturbed(pulllab: PullLab) -> None:
    pulllab.serve()
    pulllab.publisher(TOPIC, 2000)
    pulllab.publisher(OTHER, 2000)
    pulllab.served(TOPIC)
    sub = pulllab.client().subscribe(OTHER, "robot/joint_state", buffers=64)
    assert sub.read(timeout=30) is not None
    undecodable, unknown, data = bad_packets(pulllab.uri(TOPIC))
    pulllab.send(undecodable + unknown + data)
    total = len(undecodable) + len(unknown) + len(data)
    port = wait_for(lambda: (p := pulllab.counters()[0])["packets"] >= total and p,
                    "the producer counting every bad packet")
    assert (port["packets"], port["bad"], port["unknown"], port["other"]) == \
        (total, len(undecodable), len(unknown), len(data))
    topic = pulllab.counters()[1][TOPIC]
    assert topic["interests"] == topic["data"] == 0  # nothing reached the topic
    daemons = pulllab.lab.daemon_pids()
    # a flood: every datagram that arrives is counted, none is answered
    rng = random.Random(1)
    pulllab.send([garbage(rng, rng.randrange(1, 200)) for _ in range(10_000)])
    wait_for(lambda: pulllab.counters()[0]["bad"] > len(undecodable),
             "the flood being counted")
    port = pulllab.counters()[0]
    assert port["packets"] == port["bad"] + port["unknown"] + port["other"] <= total + 10_000
    # the daemon still serves the pull topic, and forwards the other topic
    with ln.pull_subscribe("127.0.0.1", pulllab.port, pulllab.uri(TOPIC),
                           "robot/joint_state") as pull:
        seqs = []
        while len(seqs) < 20:
            sample = pull.receive(30.0)
            assert sample is not None, pull.stats
            assert sample.message.cycle == sample.seq
            seqs.append(sample.seq)
    assert seqs == sorted(set(seqs))
    before = sub.info.seq
    wait_for(lambda: sub.read(timeout=1) is not None and sub.info.seq > before + 10,
             "the other topic's subscriber still getting samples")
    assert pulllab.lab.daemon_pids() == daemons
