"""The pull-topic messages of the daemon protocol (PULL_TOPIC, PULL_REMOVE, PULL_STATUS and
its PULL_LIST reply; docs/daemon.md, docs/pull.md): request encoders and the reply decoder
used by daemon_client.DaemonClient.  Little-endian; `str` is a u32 length and the bytes."""

from __future__ import annotations

import struct
from dataclasses import dataclass

from .daemon_payload import PayloadReader
from .daemon_payload import encode_str as _str

SIG_DIGEST_SHA256 = 0
SIG_HMAC_SHA256 = 4


@dataclass(frozen=True)
class PullPortStatus:
    """One UDP port of a daemon's pull producer.  packets: datagrams received; bad: did not
    decode; unknown: an Interest for a name no topic serves; other: Data or anything that is
    not an Interest."""

    address: str
    port: int
    packets: int
    bad: int
    unknown: int
    other: int
    last_error: str


@dataclass(frozen=True)
class PullTopicStatus:
    """One pull topic on a daemon and its producer's counters (overflow: Interests answered
    with a NACK because the parked table was full)."""

    topic: str
    name: str
    ring: str
    address: str
    port: int
    history: int
    latest_seq: int
    interests: int
    syncs: int
    data: int
    nacks: int
    parked: int
    expired: int
    duplicates: int
    overflow: int
    last_error: str


@dataclass(frozen=True)
class PullStatus:
    """A PULL_LIST reply: the ports and the topics asked for."""

    ports: list[PullPortStatus]
    topics: list[PullTopicStatus]


def encode_pull_topic(topic: str, ring: str, md_name: str, layout_hash: int,
                      message_size: int, address: str, port: int, name: str, history: int,
                      freshness_ms: int, key: bytes = b"") -> bytes:
    """The PULL_TOPIC payload; signature HMAC-SHA256 when `key` is given, else DigestSha256.
    struct.error for a number out of its field's range."""
    signature = SIG_HMAC_SHA256 if key else SIG_DIGEST_SHA256
    return (_str(topic) + _str(ring) + _str(md_name)
            + struct.pack("<QQ", layout_hash, message_size) + _str(address)
            + struct.pack("<H", port) + _str(name)
            + struct.pack("<IIB", history, freshness_ms, signature) + _str(key))


def decode_pull_list(payload: bytes) -> PullStatus:
    """A PULL_LIST payload; ValueError if it is short or has bytes left over."""
    r = PayloadReader(payload)
    ports = []
    for _ in range(r.take("<I")[0]):
        address = r.text()
        (port,) = r.take("<H")
        packets, bad, unknown, other = r.take("<QQQQ")
        ports.append(PullPortStatus(address, port, packets, bad, unknown, other, r.text()))
    topics = []
    for _ in range(r.take("<I")[0]):
        topic, name, ring, address = r.text(), r.text(), r.text(), r.text()
        port, history, latest = r.take("<HIQ")
        counters = r.take("<QQQQQQQQ")
        topics.append(PullTopicStatus(topic, name, ring, address, port, history, latest,
                                      *counters, r.text()))
    if r.pos != len(payload):
        raise ValueError("bytes left over")
    return PullStatus(ports, topics)


def encode_pull_list(status: PullStatus) -> bytes:
    """The PULL_LIST payload of `status` (the daemon's side; for tests and fakes)."""
    out = [struct.pack("<I", len(status.ports))]
    for p in status.ports:
        out += [_str(p.address), struct.pack("<HQQQQ", p.port, p.packets, p.bad, p.unknown,
                                             p.other), _str(p.last_error)]
    out.append(struct.pack("<I", len(status.topics)))
    for t in status.topics:
        out += [_str(t.topic), _str(t.name), _str(t.ring), _str(t.address),
                struct.pack("<HIQQQQQQQQQ", t.port, t.history, t.latest_seq, t.interests,
                            t.syncs, t.data, t.nacks, t.parked, t.expired, t.duplicates,
                            t.overflow), _str(t.last_error)]
    return b"".join(out)
