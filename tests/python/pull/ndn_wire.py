"""A small NDN packet format 0.3 TLV codec written for the pull tests from the spec, apart
from the product's C codec: the fake producer, the HMAC check and the bad packets use it,
so that a test compares two implementations, not one with itself."""

from __future__ import annotations

import hashlib
import hmac
import struct
from dataclasses import dataclass, field

INTEREST, DATA, NAME, GENERIC, SEQ = 0x05, 0x06, 0x07, 0x08, 0x3A
CAN_BE_PREFIX, MUST_BE_FRESH, NONCE, LIFETIME = 0x21, 0x12, 0x0A, 0x0C
META, CONTENT, SIG_INFO, SIG_VALUE, CONTENT_TYPE, FRESHNESS, SIG_TYPE = \
    0x14, 0x15, 0x16, 0x17, 0x18, 0x19, 0x1B
LP_PACKET, LP_FRAGMENT, LP_PIT_TOKEN = 0x64, 0x50, 0x62
PULL_LATEST, PULL_TIME, PULL_PERIOD, PULL_PAYLOAD = 0x80, 0x82, 0x84, 0x86


def varnum(n: int) -> bytes:
    if n < 253:
        return bytes([n])
    if n <= 0xFFFF:
        return b"\xfd" + struct.pack(">H", n)
    if n <= 0xFFFFFFFF:
        return b"\xfe" + struct.pack(">I", n)
    return b"\xff" + struct.pack(">Q", n)


def tlv(t: int, value: bytes = b"") -> bytes:
    return varnum(t) + varnum(len(value)) + value


def nonneg(n: int) -> bytes:
    for fmt, limit in ((">B", 0xFF), (">H", 0xFFFF), (">I", 0xFFFFFFFF)):
        if n <= limit:
            return struct.pack(fmt, n)
    return struct.pack(">Q", n)


def name_value(uri: str, seq: int | None = None, extra: tuple[str, ...] = ()) -> bytes:
    """Components of a URI of plain components (no escapes needed in the tests), then
    the generic components `extra`, then a SequenceNum if seq is given."""
    parts = [p for p in uri.split("/") if p] + list(extra)
    out = b"".join(tlv(GENERIC, p.encode()) for p in parts)
    return out + (tlv(SEQ, nonneg(seq)) if seq is not None else b"")


def interest(name: bytes, nonce: int = 1, lifetime_ms: int | None = 1000,
             can_be_prefix: bool = False, must_be_fresh: bool = False) -> bytes:
    body = tlv(NAME, name)
    body += tlv(CAN_BE_PREFIX) if can_be_prefix else b""
    body += tlv(MUST_BE_FRESH) if must_be_fresh else b""
    body += tlv(NONCE, struct.pack(">I", nonce))
    body += tlv(LIFETIME, nonneg(lifetime_ms)) if lifetime_ms is not None else b""
    return tlv(INTEREST, body)


def pull_content(latest: int, publish_us: int = 0, period_us: int = 0,
                 payload: bytes | None = None) -> bytes:
    out = tlv(PULL_LATEST, nonneg(latest))
    out += tlv(PULL_TIME, nonneg(publish_us)) if publish_us else b""
    out += tlv(PULL_PERIOD, nonneg(period_us)) if period_us else b""
    return out + (tlv(PULL_PAYLOAD, payload) if payload is not None else b"")


def data(name: bytes, content: bytes, freshness_ms: int = 0, content_type: int = 0,
         key: bytes = b"") -> bytes:
    meta = tlv(CONTENT_TYPE, nonneg(content_type)) if content_type else b""
    meta += tlv(FRESHNESS, nonneg(freshness_ms)) if freshness_ms else b""
    signed = tlv(NAME, name) + (tlv(META, meta) if meta else b"") + tlv(CONTENT, content)
    signed += tlv(SIG_INFO, tlv(SIG_TYPE, nonneg(4 if key else 0)))
    digest = hmac.new(key, signed, hashlib.sha256).digest() if key else \
        hashlib.sha256(signed).digest()
    return tlv(DATA, signed + tlv(SIG_VALUE, digest))


@dataclass
class Element:
    type: int
    value: bytes
    start: int  # offset of the TLV in the buffer it was read from
    end: int
    children: list[Element] = field(default_factory=list)

    def find(self, t: int) -> Element | None:
        return next((c for c in self.children if c.type == t), None)


def read_varnum(buf: bytes, pos: int) -> tuple[int, int]:
    first = buf[pos]
    if first < 253:
        return first, pos + 1
    size = {253: 2, 254: 4, 255: 8}[first]
    if pos + 1 + size > len(buf):
        raise ValueError("truncated VAR-NUMBER")
    return int.from_bytes(buf[pos + 1:pos + 1 + size], "big"), pos + 1 + size


def parse(buf: bytes, start: int = 0, end: int | None = None) -> list[Element]:
    """The TLVs of buf[start:end] (not recursive)."""
    end = len(buf) if end is None else end
    out, pos = [], start
    while pos < end:
        t, p = read_varnum(buf, pos)
        n, p = read_varnum(buf, p)
        if p + n > end:
            raise ValueError("truncated TLV")
        out.append(Element(t, buf[p:p + n], pos, p + n))
        pos = p + n
    return out


def packet(buf: bytes) -> tuple[Element, bytes]:
    """The Interest or Data of a datagram (unwrapping an LpPacket) and the PIT token."""
    (top,) = parse(buf)
    token = b""
    if top.type == LP_PACKET:
        fields = parse(top.value)
        token = next((f.value for f in fields if f.type == LP_PIT_TOKEN), b"")
        frag = next(f for f in fields if f.type == LP_FRAGMENT)
        (top,) = parse(frag.value)
    top.children = parse(top.value)
    return top, token


def components(name: bytes) -> list[tuple[int, bytes]]:
    return [(e.type, e.value) for e in parse(name)]


@dataclass
class DecodedData:
    name: bytes
    content_type: int
    freshness_ms: int
    content: bytes
    signature_type: int
    signature: bytes
    signed: bytes  # Name through SignatureInfo


def decode_data(buf: bytes) -> DecodedData:
    top, _ = packet(buf)
    assert top.type == DATA, f"type {top.type:#x}"
    fields = top.children
    name = top.find(NAME)
    meta = top.find(META)
    meta_fields = parse(meta.value) if meta else []
    ctype = next((int.from_bytes(m.value, "big") for m in meta_fields
                  if m.type == CONTENT_TYPE), 0)
    fresh = next((int.from_bytes(m.value, "big") for m in meta_fields
                  if m.type == FRESHNESS), 0)
    content = top.find(CONTENT)
    info = top.find(SIG_INFO)
    value = top.find(SIG_VALUE)
    assert name and info and value
    sig_type = int.from_bytes(parse(info.value)[0].value, "big")
    first = fields[0].start
    return DecodedData(name.value, ctype, fresh, content.value if content else b"", sig_type,
                       value.value, top.value[first:info.end])


def decode_pull_content(content: bytes) -> dict[int, bytes]:
    return {e.type: e.value for e in parse(content)}


def verify(d: DecodedData, key: bytes = b"") -> bool:
    want = hmac.new(key, d.signed, hashlib.sha256).digest() if d.signature_type == 4 else \
        hashlib.sha256(d.signed).digest()
    return hmac.compare_digest(want, d.signature)
