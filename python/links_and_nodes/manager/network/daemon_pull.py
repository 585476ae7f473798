"""The pull-topic messages of the daemon protocol (PULL_TOPIC, PULL_REMOVE, PULL_STATUS and
its PULL_LIST reply; docs/daemon.md, docs/pull.md): request encoders and the reply decoder
used by daemon_client.DaemonClient, on the schema-driven codec (wire/daemon.schema)."""

from __future__ import annotations

from dataclasses import dataclass

from ...wire.codec import DAEMON as _WIRE

SIG_DIGEST_SHA256 = int(_WIRE.enums["Signature"].DIGEST_SHA256)
SIG_HMAC_SHA256 = int(_WIRE.enums["Signature"].HMAC_SHA256)


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
    WireError (a struct.error) for a value that does not fit its field."""
    return _WIRE.encode("PULL_TOPIC", {
        "topic": topic, "ring": ring, "md_name": md_name, "layout_hash": layout_hash,
        "message_size": message_size, "address": address, "port": port, "name": name,
        "history": history, "freshness_ms": freshness_ms,
        "signature": SIG_HMAC_SHA256 if key else SIG_DIGEST_SHA256, "key": key})


def decode_pull_list(payload: bytes) -> PullStatus:
    """A PULL_LIST payload; WireError (a ValueError) if it is short or has bytes left over."""
    f = _WIRE.decode("PULL_LIST", payload)
    ports = [PullPortStatus(p["address"], p["port"], **p["counters"],
                            last_error=p["last_error"]) for p in f["ports"]]
    topics = [PullTopicStatus(t["topic"], t["name"], t["ring"], t["address"], t["port"],
                              t["history"], t["latest_seq"], **t["counters"],
                              last_error=t["last_error"]) for t in f["topics"]]
    return PullStatus(ports, topics)


def encode_pull_list(status: PullStatus) -> bytes:
    """The PULL_LIST payload of `status` (the daemon's side; for tests and fakes)."""
    port_counters = ("packets", "bad", "unknown", "other")
    topic_counters = ("interests", "syncs", "data", "nacks", "parked", "expired",
                      "duplicates", "overflow")
    return _WIRE.encode("PULL_LIST", {
        "ports": [{**vars(p), "counters": {c: getattr(p, c) for c in port_counters}}
                  for p in status.ports],
        "topics": [{**vars(t), "counters": {c: getattr(t, c) for c in topic_counters}}
                   for t in status.topics]})
