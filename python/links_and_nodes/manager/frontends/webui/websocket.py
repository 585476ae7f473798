"""RFC 6455 WebSocket framing for the web UI: the handshake answer, reading one message
(client frames must be masked; fragments reassembled; control frames answered in between;
every frame and message within MAX_MESSAGE) and writing unmasked server frames."""

from __future__ import annotations

import asyncio
import base64
import hashlib
import struct

GUID = "258EAFA5-E914-47DA-95CA-C5AB0DC85B11"
MAX_MESSAGE = 1 << 20  # bytes of one client message, reassembled
OP_CONT, OP_TEXT, OP_BINARY, OP_CLOSE, OP_PING, OP_PONG = 0x0, 0x1, 0x2, 0x8, 0x9, 0xA

CLOSE_NORMAL, CLOSE_PROTOCOL, CLOSE_UNSUPPORTED, CLOSE_INVALID, CLOSE_POLICY, \
    CLOSE_TOO_BIG = 1000, 1002, 1003, 1007, 1008, 1009


class WsClosed(Exception):
    """The connection ends: `code` is sent in our close frame (if we still can)."""

    def __init__(self, code: int, text: str = "") -> None:
        super().__init__(text or str(code))
        self.code = code


def accept_key(key: str) -> str:
    return base64.b64encode(hashlib.sha1((key + GUID).encode()).digest()).decode()


def valid_key(key: str) -> bool:
    try:
        return len(base64.b64decode(key, validate=True)) == 16
    except ValueError:
        return False


def frame(opcode: int, payload: bytes, fin: bool = True, mask: bytes | None = None) -> bytes:
    """One frame; `mask` (4 bytes) masks it as a client must (for tests and clients)."""
    head = bytes([(0x80 if fin else 0) | opcode])
    n = len(payload)
    bit = 0x80 if mask else 0
    if n < 126:
        head += bytes([bit | n])
    elif n < 1 << 16:
        head += bytes([bit | 126]) + struct.pack(">H", n)
    else:
        head += bytes([bit | 127]) + struct.pack(">Q", n)
    if mask:
        return head + mask + apply_mask(payload, mask)
    return head + payload


def apply_mask(payload: bytes, mask: bytes) -> bytes:
    if not payload:
        return payload
    key = (mask * (len(payload) // 4 + 1))[:len(payload)]
    return (int.from_bytes(payload, "big") ^ int.from_bytes(key, "big")).to_bytes(
        len(payload), "big")


def close_frame(code: int, reason: str = "") -> bytes:
    return frame(OP_CLOSE, struct.pack(">H", code) + reason.encode()[:120])


async def _frame(reader: asyncio.StreamReader, room: int) -> tuple[bool, int, bytes]:
    """(fin, opcode, unmasked payload) of the next client frame."""
    try:
        b0, b1 = await reader.readexactly(2)
        if b0 & 0x70:
            raise WsClosed(CLOSE_PROTOCOL, "reserved bits set")
        if not b1 & 0x80:
            raise WsClosed(CLOSE_PROTOCOL, "client frame not masked")
        n = b1 & 0x7F
        if n == 126:
            (n,) = struct.unpack(">H", await reader.readexactly(2))
        elif n == 127:
            (n,) = struct.unpack(">Q", await reader.readexactly(8))
        opcode = b0 & 0x0F
        if opcode >= 0x8 and (n > 125 or not b0 & 0x80):
            raise WsClosed(CLOSE_PROTOCOL, "control frame fragmented or over 125 bytes")
        if n > room:
            raise WsClosed(CLOSE_TOO_BIG, f"message over {MAX_MESSAGE} bytes")
        mask = await reader.readexactly(4)
        payload = await reader.readexactly(n)
    except asyncio.IncompleteReadError:
        raise WsClosed(CLOSE_PROTOCOL, "connection closed within a frame") from None
    return bool(b0 & 0x80), opcode, apply_mask(payload, mask)


async def read_message(reader: asyncio.StreamReader, writer: asyncio.StreamWriter,
                       limit: int = MAX_MESSAGE) -> str:
    """The next text message; pings are answered on the way.  WsClosed when the client
    closes or breaks the protocol (binary messages are refused: the API is JSON text)."""
    parts: list[bytes] = []
    size = 0
    opcode_of_message: int | None = None
    while True:
        fin, opcode, payload = await _frame(reader, limit - size)
        if opcode == OP_PING:
            writer.write(frame(OP_PONG, payload))
            continue
        if opcode == OP_PONG:
            continue
        if opcode == OP_CLOSE:
            code = struct.unpack(">H", payload[:2])[0] if len(payload) >= 2 else CLOSE_NORMAL
            raise WsClosed(CLOSE_NORMAL, f"closed by the client ({code})")
        if opcode == OP_CONT:
            if opcode_of_message is None:
                raise WsClosed(CLOSE_PROTOCOL, "continuation without a message")
        elif opcode in (OP_TEXT, OP_BINARY):
            if opcode_of_message is not None:
                raise WsClosed(CLOSE_PROTOCOL, "new message within a fragmented one")
            opcode_of_message = opcode
        else:
            raise WsClosed(CLOSE_PROTOCOL, f"unknown opcode {opcode}")
        parts.append(payload)
        size += len(payload)
        if fin:
            break
    if opcode_of_message == OP_BINARY:
        raise WsClosed(CLOSE_UNSUPPORTED, "binary messages are not accepted")
    try:
        return b"".join(parts).decode("utf-8")
    except UnicodeDecodeError:
        raise WsClosed(CLOSE_INVALID, "text message is not UTF-8") from None
