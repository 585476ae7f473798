"""SLIP framing (RFC 1055) of the serial link to a microcontroller (ln_pull_serial, the
firmware of firmware/pull_mcu): an encoder and an incremental decoder that drops an
oversized frame or one with a bad escape whole, counts it, and goes on at the next END."""

from __future__ import annotations

from dataclasses import dataclass, field

END, ESC, ESC_END, ESC_ESC = 0xC0, 0xDB, 0xDC, 0xDD


def encode(frame: bytes) -> bytes:
    """One frame on the wire: END, the escaped bytes, END (the leading END flushes noise)."""
    body = frame.replace(bytes([ESC]), bytes([ESC, ESC_ESC])).replace(
        bytes([END]), bytes([ESC, ESC_END])
    )
    return bytes([END]) + body + bytes([END])


@dataclass
class Decoder:
    """Feed it bytes as they come; it returns the frames they complete (never empty ones)."""

    max_frame: int = 2048
    oversized: int = 0
    bad_escape: int = 0
    _buf: bytearray = field(default_factory=bytearray)
    _escaped: bool = False
    _dropping: bool = False

    def feed(self, data: bytes) -> list[bytes]:
        frames = []
        for c in data:
            if c == END:
                if self._escaped:
                    self.bad_escape += 1
                elif self._buf and not self._dropping:
                    frames.append(bytes(self._buf))
                self._buf.clear()
                self._escaped = self._dropping = False
            elif self._dropping:
                continue
            elif self._escaped:
                self._escaped = False
                if c not in (ESC_END, ESC_ESC):
                    self.bad_escape += 1
                    self._dropping = True
                else:
                    self._append(END if c == ESC_END else ESC)
            elif c == ESC:
                self._escaped = True
            else:
                self._append(c)
        return frames

    def _append(self, c: int) -> None:
        if len(self._buf) >= self.max_frame:
            self.oversized += 1
            self._dropping = True
            self._buf.clear()
        else:
            self._buf.append(c)
