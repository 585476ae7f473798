"""Our consumer (libln_pull's DIT core through links_and_nodes.pull) reads from a producer
built on python-ndn's packet encoder and signers: python-ndn parses our Interests and makes
the Data (sync replies, samples, NACKs), with DigestSha256 and with HMAC-SHA256.  python-ndn
has no producer that runs without a forwarder, so the socket loop is ours."""

from __future__ import annotations

import socket
import struct
import threading
import time
from typing import Any

import pytest

import links_and_nodes as ln

from . import ndn_wire as w
from .ndn_peer import ndn

URI = "/ln/peer/arm.state"


class NdnProducer:
    def __init__(self, key: bytes = b"") -> None:
        pkg = ndn()
        self.enc = pkg.encoding
        self.signer = pkg.security.HmacSha256Signer("/k", key) if key else \
            pkg.security.DigestSha256Signer()
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.005)
        self.port = self.sock.getsockname()[1]
        self.latest = 0
        self.parked: list[tuple[int, Any, tuple[str, int]]] = []
        self.interests: list[str] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> NdnProducer:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()
        self.sock.close()

    def _content(self, seq: int) -> bytes:
        return w.pull_content(self.latest, 1_000_000 * seq, 10_000, struct.pack("<Q", seq * 3))

    def _reply(self, name: Any, content: bytes, fresh: int, to: tuple[str, int],
               ctype: int = 0) -> None:
        meta = self.enc.MetaInfo(content_type=ctype, freshness_period=fresh)
        self.sock.sendto(bytes(self.enc.make_data(name, meta, content, signer=self.signer)), to)

    def _run(self) -> None:
        nxt = time.monotonic()
        while not self._stop.is_set():
            if time.monotonic() >= nxt:
                nxt += 0.01
                self.latest += 1
                for p in [p for p in self.parked if p[0] == self.latest]:
                    self.parked.remove(p)
                    self._reply(p[1], self._content(self.latest), 1000, p[2])
            try:
                buf, src = self.sock.recvfrom(9000)
            except TimeoutError:
                continue
            name, param, _, _ = self.enc.parse_interest(buf)
            self.interests.append(self.enc.Name.to_str(name))
            last = name[-1]
            if self.enc.Component.get_type(last) == self.enc.Component.TYPE_GENERIC and \
                    bytes(self.enc.Component.get_value(last)) == b"sync":
                assert param.can_be_prefix and param.must_be_fresh
                reply = [*name, self.enc.Component.from_sequence_num(self.latest)]
                self._reply(reply, self._content(self.latest), 0, src)
                continue
            seq = self.enc.Component.to_number(last)
            if seq <= self.latest - 8:
                self._reply(name, w.pull_content(self.latest), 0, src, 3)
            elif seq <= self.latest:
                self._reply(name, self._content(seq), 1000, src)
            else:
                self.parked.append((seq, name, src))


@pytest.mark.parametrize("key", [b"", b"shared-secret"])
def test_our_consumer_reads_a_python_ndn_producer(key: bytes) -> None:
    with NdnProducer(key) as prod, \
            ln.pull_subscribe("127.0.0.1", prod.port, URI, None) as sub:
        got = []
        while len(got) < 20:
            sample = sub.receive(10.0)
            assert sample is not None, sub.stats
            got.append(sample)
    seqs = [s.seq for s in got]
    assert seqs == sorted(set(seqs))
    for s in got:
        assert s.message == struct.pack("<Q", s.seq * 3)
        assert s.publish_time == s.seq  # 1e6 µs per seq, as the producer wrote it
    assert f"{URI}/sync" in prod.interests
    assert any(i.startswith(f"{URI}/seq=") for i in prod.interests)
    assert sub.stats.bad == 0
