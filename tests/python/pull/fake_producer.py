"""A pull-topic producer written in Python for the consumer tests (ndn_wire's encoder, not
the product's): publishes samples on a timer, answers /<name>/sync with the latest and
/<name>/seq=N with sample N (parked until it is published), NACKs seqs older than its
history, and counts what it got."""

from __future__ import annotations

import contextlib
import socket
import threading
import time

from . import ndn_wire as w


class FakeProducer:
    def __init__(self, uri: str, payload_of: object, period_s: float = 0.01,
                 history: int = 16, key: bytes = b"", lp: bool = False) -> None:
        self.uri = uri
        self.payload_of = payload_of  # seq -> bytes
        self.period_s = period_s
        self.history = history
        self.key = key
        self.lp = lp  # answer inside an LpPacket with a PIT token, as NFD may
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.005)
        self.port = self.sock.getsockname()[1]
        self.prefix = w.name_value(uri)
        self.latest = 0
        self.published: dict[int, tuple[bytes, int]] = {}  # seq -> (payload, publish µs)
        self.parked: list[tuple[int, tuple[str, int], float, bytes]] = []
        self.interests = self.syncs = self.nacks = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> FakeProducer:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()
        self.sock.close()

    def _publish(self) -> None:
        self.latest += 1
        self.published[self.latest] = (self.payload_of(self.latest),  # type: ignore[operator]
                                       time.time_ns() // 1000)
        self.published.pop(self.latest - self.history, None)
        for entry in [p for p in self.parked if p[0] == self.latest]:
            self.parked.remove(entry)
            self._sample(entry[3], self.latest, entry[1], b"")

    def _content(self, seq: int) -> bytes:
        payload, publish_us = self.published[seq]
        return w.pull_content(self.latest, publish_us, int(self.period_s * 1e6), payload)

    def _send(self, packet: bytes, to: tuple[str, int], token: bytes) -> None:
        if self.lp or token:
            packet = w.tlv(w.LP_PACKET, w.tlv(w.LP_PIT_TOKEN, token or b"\x01\x02")
                           + w.tlv(w.LP_FRAGMENT, packet))
        self.sock.sendto(packet, to)

    def _sample(self, name: bytes, seq: int, to: tuple[str, int], token: bytes) -> None:
        self._send(w.data(name, self._content(seq), 1000, key=self.key), to, token)

    def _run(self) -> None:
        next_pub = time.monotonic()
        while not self._stop.is_set():
            now = time.monotonic()
            if now >= next_pub:
                self._publish()
                next_pub += self.period_s
            self.parked = [p for p in self.parked if p[2] > now]
            with contextlib.suppress(TimeoutError):
                buf, src = self.sock.recvfrom(9000)
                self._handle(buf, src)

    def _handle(self, buf: bytes, src: tuple[str, int]) -> None:
        top, token = w.packet(buf)
        if top.type != w.INTEREST:
            return
        self.interests += 1
        name = top.find(w.NAME)
        assert name is not None
        lifetime = top.find(w.LIFETIME)
        life_s = int.from_bytes(lifetime.value, "big") / 1000 if lifetime else 4.0
        if not name.value.startswith(self.prefix):
            return
        last_type, last = w.components(name.value)[-1]
        if last_type == w.GENERIC and last == b"sync" and self.latest:
            self.syncs += 1
            reply = w.name_value(self.uri, self.latest, ("sync",))
            self._send(w.data(reply, self._content(self.latest), 0, key=self.key), src,
                       token)
        elif last_type == w.SEQ:
            seq = int.from_bytes(last, "big")
            if seq in self.published:
                self._sample(name.value, seq, src, token)
            elif seq <= self.latest or seq > self.latest + self.history:
                self.nacks += 1
                self._send(w.data(name.value, w.pull_content(self.latest), 0, 3,
                                  key=self.key), src, token)
            else:
                self.parked.append((seq, src, time.monotonic() + life_s, name.value))
