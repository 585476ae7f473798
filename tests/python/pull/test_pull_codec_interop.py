"""Golden vectors: packets python-ndn makes decode with our C codec (ln/ndn.h via ctypes),
and packets our codec makes parse and verify with python-ndn; plus the pull content layout
against the independent encoder of ndn_wire.py and the reference's byte strings."""

from __future__ import annotations

import ctypes
import hashlib
import hmac

import pytest

from . import ndn_ctypes as C
from . import ndn_wire as w
from .ndn_peer import ndn

# docs reference §3.6, made by python-ndn 0.5.2
SEQ_INTEREST = "051c0711080272740807636d645f76656c3a0204d20a04010203040c0164"
SYNC_INTEREST = "05220713080272740807636d645f76656c080473796e63210012000a04010203040c0164"


def test_reference_vectors_decode_and_encode_byte_for_byte() -> None:
    d = C.Decoded(bytes.fromhex(SEQ_INTEREST))
    assert d.rc == 0 and d.packet.type == 0x05
    i = d.packet.interest
    assert (i.nonce, i.lifetime_ms, i.can_be_prefix, i.must_be_fresh) == (0x01020304, 100, 0, 0)
    assert i.name.get() == C.name_from_uri("/rt/cmd_vel/seq=1234")
    assert C.encode_interest(i.name.get(), 0x01020304, 100).hex() == SEQ_INTEREST
    d = C.Decoded(bytes.fromhex(SYNC_INTEREST))
    i = d.packet.interest
    assert (i.can_be_prefix, i.must_be_fresh) == (1, 1)
    assert C.encode_interest(C.name_from_uri("/rt/cmd_vel/sync"), 0x01020304, 100, True,
                             True).hex() == SYNC_INTEREST


@pytest.mark.parametrize("seq", [0, 1, 252, 253, 255, 256, 65535, 65536, 2**32, 2**64 - 1])
def test_python_ndn_interests_decode_with_our_codec(seq: int) -> None:
    enc = ndn().encoding
    name = [enc.Component.from_str("ln"), enc.Component.from_str("a.b"),
            enc.Component.from_sequence_num(seq)]
    wire = bytes(enc.make_interest(name, enc.InterestParam(nonce=0xDEADBEEF, lifetime=1234)))
    d = C.Decoded(wire)
    assert d.rc == 0 and d.packet.type == 0x05
    assert d.packet.interest.name.get() == C.name_from_uri(f"/ln/a.b/seq={seq}")
    assert (d.packet.interest.nonce, d.packet.interest.lifetime_ms) == (0xDEADBEEF, 1234)
    assert C.encode_interest(d.packet.interest.name.get(), 0xDEADBEEF, 1234) == wire


@pytest.mark.parametrize("key", [b"", b"secret-key-0123456789"])
def test_python_ndn_data_verifies_with_our_codec(key: bytes) -> None:
    pkg = ndn()
    enc, sec = pkg.encoding, pkg.security
    signer = sec.HmacSha256Signer("/key", key) if key else sec.DigestSha256Signer()
    content = w.pull_content(9, 1_700_000_000_000_000, 20_000, b"\x01\x02\x03")
    wire = bytes(enc.make_data("/ln/robot/arm.state/sync/seq=9",
                               enc.MetaInfo(freshness_period=0), content, signer=signer))
    d = C.Decoded(wire)
    assert d.rc == 0 and d.packet.type == 0x06
    data = d.packet.data
    assert data.content.get() == content
    assert data.signature_type == (4 if key else 0)
    s = C.Signer(4 if key else 0, ctypes.cast(ctypes.c_char_p(key), C.c_u8p), len(key))
    assert C.ln_ndn_verify(ctypes.byref(data), ctypes.byref(s)) == 0
    pc = C.PullContent()
    assert C.ln_ndn_decode_pull_content(data.content, ctypes.byref(pc)) == 0
    assert (pc.latest_seq, pc.publish_us, pc.period_us, pc.payload.get()) == \
        (9, 1_700_000_000_000_000, 20_000, b"\x01\x02\x03")
    wrong = C.Signer(4 if key else 0, ctypes.cast(ctypes.c_char_p(b"other"), C.c_u8p), 5)
    if key:
        assert C.ln_ndn_verify(ctypes.byref(data), ctypes.byref(wrong)) != 0


@pytest.mark.parametrize("key", [b"", b"k" * 32])
def test_our_data_parses_and_verifies_with_python_ndn(key: bytes) -> None:
    enc = ndn().encoding
    name = C.name_from_uri("/ln/robot/arm.state/seq=77")
    content = C.encode_pull_content(80, 123456789, 10000, b"payload")
    wire = C.encode_data(name, content, 1000, key=key)
    got_name, meta, got_content, sig = enc.parse_data(wire)
    assert enc.Name.to_str(got_name) == "/ln/robot/arm.state/seq=77"
    assert meta.freshness_period == 1000 and bytes(got_content) == content
    assert sig.signature_info.signature_type == (4 if key else 0)
    signed = b"".join(bytes(p) for p in sig.signature_covered_part)
    want = hmac.new(key, signed, hashlib.sha256).digest() if key else \
        hashlib.sha256(signed).digest()
    assert bytes(sig.signature_value_buf) == want
    assert w.decode_pull_content(bytes(got_content)) == {
        w.PULL_LATEST: bytes([80]), w.PULL_TIME: (123456789).to_bytes(4, "big"),
        w.PULL_PERIOD: (10000).to_bytes(2, "big"), w.PULL_PAYLOAD: b"payload"}


def test_nack_data_and_our_interests_parse_with_python_ndn() -> None:
    enc = ndn().encoding
    nack = C.encode_data(C.name_from_uri("/ln/x/seq=3"), C.encode_pull_content(9, 0, 0, None),
                         0, 3)
    _, meta, content, _ = enc.parse_data(nack)
    assert meta.content_type == 3 and not meta.freshness_period
    assert w.decode_pull_content(bytes(content)) == {w.PULL_LATEST: b"\x09"}
    wire = C.encode_interest(C.name_from_uri("/ln/x/sync"), 7, 300, True, True)
    name, param, _, _ = enc.parse_interest(wire)
    assert enc.Name.to_str(name) == "/ln/x/sync"
    assert (param.can_be_prefix, param.must_be_fresh, param.nonce, param.lifetime) == \
        (True, True, 7, 300)


def test_our_encoder_agrees_with_the_independent_one() -> None:
    name = w.name_value("/ln/r/t", 5)
    assert C.name_from_uri("/ln/r/t/seq=5") == name
    content = w.pull_content(5, 99, 7, b"xyz")
    assert C.encode_pull_content(5, 99, 7, b"xyz") == content
    for key in (b"", b"abc"):
        assert C.encode_data(name, content, 1000, key=key) == w.data(name, content, 1000,
                                                                      key=key)
