"""Reading one message of the client<->manager protocol from a blocking socket: the frame
header, then the payload, decoded with protocol.py's codec (ln_services, the scripting
client)."""

from __future__ import annotations

import socket

from . import protocol as p


def _exactly(sock: socket.socket, count: int, error: type[Exception]) -> bytes:
    data = bytearray()
    while len(data) < count:
        chunk = sock.recv(min(count - len(data), 1 << 16))
        if not chunk:
            raise error("the manager closed the connection")
        data += chunk
    return bytes(data)


def receive(sock: socket.socket, error: type[Exception]) -> p.Message:
    """The next message from the manager on a blocking socket; `error` with the reason when
    the connection ends or the frame is malformed (socket errors and timeouts pass)."""
    try:
        length = p.frame_length(_exactly(sock, p.HEADER_SIZE, error))
        return p.decode_payload(_exactly(sock, length, error))
    except p.ProtocolError as exc:
        raise error(f"malformed answer from the manager: {exc}") from None
