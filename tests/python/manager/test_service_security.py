"""The manager's service key (registry/service_security.py): the level an instance gets, the
SERVICE_KEY_INFO answer at each level, and the key sealed under a session key exactly as
libln's svc_key.c opens it (nonce, key XOR HMAC pad, HMAC tag)."""

from __future__ import annotations

import hashlib
import hmac

import pytest

from links_and_nodes.manager.registry.service_security import ServiceSecurity, seal
from links_and_nodes.tools import protocol as p


def test_levels_and_default() -> None:
    assert ServiceSecurity.for_instance(None).level == "authenticate"
    assert ServiceSecurity.for_instance("encrypt").level == "encrypt"
    with pytest.raises(ValueError, match="security must be one of none, authenticate, encrypt"):
        ServiceSecurity("strong")
    with pytest.raises(ValueError, match="32 bytes, not 5"):
        ServiceSecurity("none", b"short")
    assert ServiceSecurity().key != ServiceSecurity().key  # fresh at every start


@pytest.mark.parametrize("level,code", [("none", p.SECURITY_NONE),
                                        ("authenticate", p.SECURITY_AUTHENTICATE),
                                        ("encrypt", p.SECURITY_ENCRYPT)])
def test_info_as_is(level: str, code: int) -> None:
    sec = ServiceSecurity(level, bytes(range(32)))
    info = sec.info(7, None)
    assert (info.request_id, info.security, info.sealed) == (7, code, 0)
    assert info.key == ("" if level == "none" else bytes(range(32)).hex())
    assert p.decode_frame(p.encode(info)) == info


def test_info_sealed_under_the_session_key() -> None:
    session, key = b"\x07" * 32, bytes(range(32))
    info = ServiceSecurity("encrypt", key).info(3, session)
    assert info.sealed == 1
    raw = bytes.fromhex(info.key)
    assert len(raw) == 80 and key.hex() not in info.key
    nonce, box, tag = raw[:16], raw[16:48], raw[48:]
    level = bytes([p.SECURITY_ENCRYPT])
    assert hmac.compare_digest(
        tag, hmac.digest(session, b"ln service key tag v2" + level + nonce + box,
                         hashlib.sha256))
    pad = hmac.digest(session, b"ln service key pad v1" + nonce, hashlib.sha256)
    assert bytes(a ^ b for a, b in zip(box, pad, strict=True)) == key
    assert seal(session, key, p.SECURITY_ENCRYPT, nonce) == raw  # deterministic for a nonce
    assert seal(session, key, p.SECURITY_NONE, nonce) != raw  # the level is tagged
    assert seal(session, key, p.SECURITY_ENCRYPT) != raw  # a fresh nonce each time


def test_level_none_is_sealed_too_for_a_session() -> None:
    info = ServiceSecurity("none", bytes(range(32))).info(4, b"\x07" * 32)
    assert (info.security, info.sealed, len(bytes.fromhex(info.key))) == \
        (p.SECURITY_NONE, 1, 80)
