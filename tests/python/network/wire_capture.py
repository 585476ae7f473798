"""A UDP relay for the network tests that keeps what it passes on: datagrams arriving at
LISTEN go on to TARGET unchanged, and their first CAP bytes are appended to OUT, so a test can
look at what crossed the wire.  Writes READY once it listens."""

from __future__ import annotations

import argparse
import socket
from pathlib import Path

SO_RCVBUFFORCE = 33  # Linux; not in the socket module


def _address(text: str) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    return host, int(port)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("listen")
    parser.add_argument("target")
    parser.add_argument("out", type=Path)
    parser.add_argument("ready", type=Path)
    parser.add_argument("--cap", type=int, default=4 << 20)
    args = parser.parse_args()
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:  # a whole 8 MiB sample arrives in one burst: room for it (FORCE needs root)
        sock.setsockopt(socket.SOL_SOCKET, SO_RCVBUFFORCE, 32 << 20)
    except OSError:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 32 << 20)
    sock.bind(_address(args.listen))
    out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    target = _address(args.target)
    kept = 0
    with args.out.open("wb") as sink:
        args.ready.write_text("listening\n")
        while True:
            data = sock.recv(65536)
            out.sendto(data, target)
            if kept < args.cap:
                sink.write(data[:args.cap - kept])
                sink.flush()
                kept += len(data)


if __name__ == "__main__":
    main()
