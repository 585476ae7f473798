"""The primitives of daemon protocol payloads (docs/daemon.md, "Frames"): little-endian
numbers, `str` as a u32 length and the bytes.  Shared by every message codec of the
manager's daemon client (daemon_client.py, daemon_pull.py)."""

from __future__ import annotations

import struct


class Malformed(ValueError):
    """A payload that is short, too long or not what its message type says."""


def encode_str(s: str | bytes) -> bytes:
    # surrogateescape: what os.environ, sys.argv and os.fsdecode make of bytes that are
    # not UTF-8 goes back as those bytes
    b = s.encode(errors="surrogateescape") if isinstance(s, str) else s
    return struct.pack("<I", len(b)) + b


class PayloadReader:
    """Little-endian payload reader; any short read raises Malformed."""

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.pos = 0

    def take(self, fmt: str) -> tuple:
        size = struct.calcsize(fmt)
        if self.pos + size > len(self.data):
            raise Malformed("short payload")
        values = struct.unpack_from(fmt, self.data, self.pos)
        self.pos += size
        return values

    def bytes(self) -> bytes:
        (n,) = self.take("<I")
        if self.pos + n > len(self.data):
            raise Malformed("short payload")
        out = self.data[self.pos:self.pos + n]
        self.pos += n
        return out

    def text(self) -> str:
        return self.bytes().decode(errors="replace")
