"""Python consumer of pull topics (docs/pull.md): `pull_subscribe(host, port, "/ln/robot/
arm.state", "robot/joint_state")` pulls a topic that an ln_daemon (or any NDN producer
naming samples the same way) serves over UDP, with libln_pull's Dynamic Interest Timeout
core doing the pulling; this module only owns the socket and the clock and decodes samples
with the message definition.

    with ln.pull_subscribe("robot-pc", 6363, "/ln/lab/arm.state", "robot/joint_state") as sub:
        for sample in sub:
            print(sample.seq, sample.age, sample.message.position)
"""

from __future__ import annotations

import collections
import ctypes
import random
import select
import socket
import time
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

from . import _pull_lib as P

MAX_DATAGRAM = 65535
QUEUE = 256  # samples kept for a reader that falls behind (the oldest go first)


@dataclass(frozen=True)
class PullSample:
    """One sample: its seq at the producer, the message (decoded with the md, or the bytes
    when md is None), its publish time (CLOCK_REALTIME seconds, the publisher's timestamp)
    and its age when it arrived (seconds; the two hosts' clocks must agree for it to mean
    anything across hosts)."""

    seq: int
    message: Any
    publish_time: float
    age: float


@dataclass(frozen=True)
class PullStats:
    """The consumer core's counters (ln_pull_stats), its current DIT timeout and the
    producer's newest seq as last reported; mismatched: samples whose size is not the md's;
    dropped: samples evicted from the queue unread; refused: ICMP port unreachable."""

    interests: int
    syncs: int
    data: int
    timeouts: int
    nacks: int
    late: int
    bad: int
    t_ms: int
    latest_seq: int
    mismatched: int
    dropped: int
    refused: int
    refreshes: int = 0  # pending Interests sent once more (LN_PULL_REFRESH)


def make_options(naive: bool = False, window: int = 3, deadline_ms: int = 1000, poll_ms: int = 0,
            overrides: Mapping[str, int] | None = None) -> P.Options:
    """The core's options: the seed's DIT (`naive`), or every hardening with `window`
    outstanding Interests and t_max = `deadline_ms`; `poll_ms` > 0 polls /sync at a fixed
    rate instead; `overrides` sets fields of ln_pull_options by name last."""
    o = P.Options()
    if naive:
        P.ln_pull_options_naive(ctypes.byref(o))
    else:
        P.ln_pull_options_hardened(ctypes.byref(o), deadline_ms)
        o.window = window
    o.poll_ms = poll_ms
    for name, value in (overrides or {}).items():
        if name not in {f[0] for f in P.Options._fields_}:
            raise ValueError(f"unknown pull option {name!r}")
        setattr(o, name, value)
    return o


class PullSubscription:
    """A pull subscription; iterate it (blocking) or call receive(timeout).  Not thread-safe:
    one thread drives it."""

    def __init__(self, host: str, port: int, uri: str, md: Any, opts: P.Options,
                 seed: int | None = None) -> None:
        self.uri = uri
        self.message_class = _message_class(md)
        family, kind, proto, _, address = socket.getaddrinfo(host, port,
                                                             type=socket.SOCK_DGRAM)[0]
        self._sock = socket.socket(family, kind, proto)
        self._sock.connect(address)
        self._sock.setblocking(False)
        self._fd = ctypes.c_int(self._sock.fileno())
        self._samples: collections.deque[PullSample] = collections.deque()
        self._mismatched = self._dropped = self._refused = 0
        self._sub = P.Sub()
        self._on_data = P.DataFn(self._data)
        self._on_event = P.EventFn(lambda user, event, seq, t_ms: None)
        rc = P.ln_pull_start(ctypes.byref(self._sub), uri.encode(), ctypes.byref(opts),
                             P.udp_send, self._on_data, self._on_event,
                             ctypes.cast(ctypes.byref(self._fd), ctypes.c_void_p),
                             P.ln_pull_udp_now_ms(),
                             seed if seed is not None else random.getrandbits(32))
        if rc < 0:
            self._sock.close()
            raise ValueError(f"cannot pull {uri!r}: {P.strerror(rc)}")

    def _data(self, user: Any, seq: int, payload: Any, size: int, publish_us: int) -> None:
        now = time.time()
        data = ctypes.string_at(payload, size) if size else b""
        cls = self.message_class
        if cls is not None and len(data) != ctypes.sizeof(cls):
            self._mismatched += 1
            return
        message = cls.from_buffer_copy(data) if cls is not None else data
        if len(self._samples) >= QUEUE:
            self._samples.popleft()
            self._dropped += 1
        publish = publish_us / 1e6
        self._samples.append(PullSample(seq, message, publish, now - publish))

    def receive(self, timeout: float | None = None) -> PullSample | None:
        """The next sample, or None if none came within `timeout` seconds (None: wait)."""
        if self._sock.fileno() < 0:
            raise ValueError("the pull subscription is closed")
        deadline = None if timeout is None else time.monotonic() + timeout
        while not self._samples:
            wait = P.ln_pull_poll(ctypes.byref(self._sub), P.ln_pull_udp_now_ms()) / 1000
            if self._samples:
                break
            if deadline is not None:
                left = deadline - time.monotonic()
                if left <= 0:
                    return None
                wait = min(wait, left)
            ready, _, _ = select.select([self._sock], [], [], max(wait, 0.0))
            if ready:
                self._drain()
        return self._samples.popleft()

    def _drain(self) -> None:
        while True:
            try:
                packet = self._sock.recv(MAX_DATAGRAM)
            except BlockingIOError:
                return
            except ConnectionRefusedError:  # nobody at the port (yet): a timeout will tell
                self._refused += 1
                continue
            P.ln_pull_receive(ctypes.byref(self._sub), packet, len(packet),
                              P.ln_pull_udp_now_ms())

    def __iter__(self) -> Iterator[PullSample]:
        while True:
            sample = self.receive()
            if sample is not None:
                yield sample

    @property
    def stats(self) -> PullStats:
        s = self._sub.stats
        return PullStats(s.interests, s.syncs, s.data, s.timeouts, s.nacks, s.late, s.bad,
                         self._sub.t_ms, self._sub.latest_seq, self._mismatched,
                         self._dropped, self._refused, s.refreshes)

    def close(self) -> None:
        self._sock.close()

    def __enter__(self) -> PullSubscription:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _message_class(md: Any) -> Any:
    """An md name is looked up like everywhere in the API; a message class is used as it is;
    None gives the payload bytes."""
    if md is None or isinstance(md, type):
        return md
    from .md_loader import message_class

    return message_class(md)


def pull_subscribe(host: str, port: int, uri: str, md: Any,
                   options: Mapping[str, int] | None = None, *, window: int = 3,
                   deadline_ms: int = 1000, naive: bool = False, poll_ms: int = 0,
                   seed: int | None = None) -> PullSubscription:
    """Pull the topic named `uri` ("/<prefix>/<topic>") from the producer at host:port.
    By default every hardening of docs/pull.md with `window` outstanding Interests and the
    DIT timeout capped at `deadline_ms`; `naive` is the seed's DIT, `poll_ms` > 0 a fixed-
    rate poll; `options` overrides fields of ln_pull_options by name."""
    return PullSubscription(host, port, uri, md,
                            make_options(naive, window, deadline_ms, poll_ms, options),
                            seed)
