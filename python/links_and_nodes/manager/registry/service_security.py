"""The instance's service key: a random 32-byte key made when the manager starts, and the
security level (docs/security.md, "Remote service calls") with which providers and callers
protect service calls between hosts.  Clients ask for both with SERVICE_KEY; a client whose
connection has a session key (client admission) gets the key sealed under it."""

from __future__ import annotations

import hashlib
import hmac
import secrets
from dataclasses import dataclass, field

from ...tools import protocol as p

LEVELS = {"none": p.SECURITY_NONE, "authenticate": p.SECURITY_AUTHENTICATE,
          "encrypt": p.SECURITY_ENCRYPT}
DEFAULT_LEVEL = "authenticate"  # an instance without a `security:` setting
KEY_BYTES: int = p.SERVICE_KEY_BYTES
_PAD_LABEL = b"ln service key pad v1"
_TAG_LABEL = b"ln service key tag v2"
_NONCE_BYTES = 16


def seal(session_key: bytes, key: bytes, level: int, nonce: bytes | None = None) -> bytes:
    """`key` sealed under a client's session key: nonce, key XOR pad, tag (80 bytes); the tag
    covers the level code too, so nobody on the way can lower it.  libln's svc_key.c opens
    it.  Stdlib only: HMAC-SHA256 makes the pad and the tag."""
    nonce = secrets.token_bytes(_NONCE_BYTES) if nonce is None else nonce
    pad = hmac.digest(session_key, _PAD_LABEL + nonce, hashlib.sha256)
    box = bytes(a ^ b for a, b in zip(key, pad, strict=True))
    tag = hmac.digest(session_key, _TAG_LABEL + bytes([level]) + nonce + box, hashlib.sha256)
    return nonce + box + tag


@dataclass(frozen=True)
class ServiceSecurity:
    """The level name ("none", "authenticate", "encrypt") and this manager's key."""

    level: str = DEFAULT_LEVEL
    key: bytes = field(default_factory=lambda: secrets.token_bytes(KEY_BYTES), repr=False)

    def __post_init__(self) -> None:
        if self.level not in LEVELS:
            raise ValueError(f"security must be one of {', '.join(LEVELS)}, not {self.level!r}")
        if len(self.key) != KEY_BYTES:
            raise ValueError(f"a service key has {KEY_BYTES} bytes, not {len(self.key)}")

    @classmethod
    def for_instance(cls, level: str | None) -> ServiceSecurity:
        """A fresh key for an instance whose `security:` is `level` (None: the default)."""
        return cls(level if level is not None else DEFAULT_LEVEL)

    def info(self, request_id: int, session_key: bytes | None) -> p.Message:
        """The SERVICE_KEY_INFO answer: sealed under the session key if there is one (the
        level included), else as is; no key at all with level none."""
        level = LEVELS[self.level]
        if session_key:  # always sealed: the seal authenticates the level, none included
            return p.ServiceKeyInfo(request_id, level, 1,
                                    seal(session_key, self.key, level).hex())
        if level == p.SECURITY_NONE:
            return p.ServiceKeyInfo(request_id, level, 0, "")
        return p.ServiceKeyInfo(request_id, level, 0, self.key.hex())
