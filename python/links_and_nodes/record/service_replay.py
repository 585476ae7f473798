"""ln_play --services: the recorded service calls issued again to the live services at their
recorded times (docs/recording.md, "Service calls").  Each request goes out as recorded, in
its wire form, over the service protocol (HELLO with the recorded layout hash, REQUEST), so
the provider checks it exactly as it checked the original; responses are not compared.

The calls follow the topic playback's replay time (pause, rate, seek) while it plays, and go
on at the same rate on their own once it has finished or when there are no topics."""

from __future__ import annotations

import bisect
import socket
import struct
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..addresses import parse_manager_address
from ..mcap_format import McapReader
from .service_calls import (
    _ERROR,
    _FRAME,
    _SVC_MAGIC,
    _SVC_VERSION,
    CallFormatError,
    ServiceCall,
    ServiceDirectory,
    _Frames,
    _str,
    connect_provider,
    decode_call,
    local_host_id,
)

_HELLO, _WELCOME, _REQUEST, _RESPONSE = 1, 2, 3, 4
TICK = 0.005  # seconds between looks at the replay time
CALL_TIMEOUT = 10.0


@dataclass(frozen=True)
class Recorded:
    time_ns: int
    call: ServiceCall


def recorded_calls(readers: list[McapReader]) -> list[Recorded]:
    """Every recorded call of the files, in time order; CallFormatError names file and
    channel of one that does not decode."""
    out: list[Recorded] = []
    for reader in readers:
        infos = {n: i for n, i in reader.topics().items() if i.kind == "service"}
        for n, sample in enumerate(reader.samples(list(infos))):
            info = infos[sample.topic]
            try:
                call = decode_call(sample.data, info.topic, info.md_name, info.layout_hash)
            except CallFormatError as exc:
                raise CallFormatError(f"{reader.path}: service '{info.topic}', call {n}: "
                                      f"{exc}") from None
            out.append(Recorded(call.request_time_ns, call))
    out.sort(key=lambda r: r.time_ns)
    return out


class _Connection:
    """A caller connection to one service, opened on first use and after any failure."""

    def __init__(self, directory: ServiceDirectory, service: str, layout_hash: int) -> None:
        self.directory, self.service, self.layout_hash = directory, service, layout_hash
        self.sock: socket.socket | None = None
        self.frames = _Frames()
        self.call_id = 0

    def _open(self) -> socket.socket:
        entry = next((e for e in self.directory.services() if e.name == self.service), None)
        if entry is None:
            raise ConnectionError(f"service '{self.service}' is not provided")
        sock = connect_provider(entry, local_host_id())
        sock.settimeout(CALL_TIMEOUT)
        body = (struct.pack("<IH", _SVC_MAGIC, _SVC_VERSION) + _str(self.service)
                + struct.pack("<Q", self.layout_hash) + _str("ln_play"))
        sock.sendall(_FRAME.pack(len(body) + 2, _HELLO) + body)
        self.frames = _Frames()
        kind, answer = self._frame(sock)
        if kind != _WELCOME:
            sock.close()
            raise ConnectionError(f"service '{self.service}': {_error_text(answer)}")
        return sock

    def _frame(self, sock: socket.socket) -> tuple[int, bytes]:
        while True:
            for frame in self.frames.feed(b""):
                return frame
            chunk = sock.recv(1 << 20)
            if not chunk:
                raise ConnectionError("the provider closed the connection")
            self.frames.buf += chunk

    def call(self, request: bytes) -> str | None:
        """Issue one request; None, or why it failed (an error answer's text)."""
        try:
            if self.sock is None:
                self.sock = self._open()
            self.call_id = self.call_id % 0xFFFFFFFF + 1
            body = struct.pack("<I", self.call_id) + request
            self.sock.sendall(_FRAME.pack(len(body) + 2, _REQUEST) + body)
            kind, answer = self._frame(self.sock)
        except (OSError, ConnectionError, ValueError) as exc:
            self.close()
            return str(exc)
        if kind == _RESPONSE:
            return None
        if kind != _ERROR:
            self.close()
        return _error_text(answer)

    def close(self) -> None:
        if self.sock is not None:
            self.sock.close()
            self.sock = None


def _error_text(body: bytes) -> str:
    try:
        _, code, n = struct.unpack_from("<IiH", body)
        return f"error {code}: {body[10:10 + n].decode('utf-8', 'replace')}"
    except struct.error:
        return "malformed answer"


class ServiceReplay:
    """Issues `calls` (recorded_calls) again in a thread, when `position()` (the replay time
    of the topic playback) reaches their time; `finished()` true means the playback clock
    stopped, after which time goes on at `rate` from where it was."""

    def __init__(self, manager: str, calls: list[Recorded], begin_ns: int,
                 position: Callable[[], int], finished: Callable[[], bool], rate: float,
                 on_error: Callable[[str], None] = lambda text: None) -> None:
        self.calls, self.begin_ns = calls, begin_ns
        self.times = [c.time_ns for c in calls]
        self.position, self.finished, self.rate = position, finished, rate
        self.on_error = on_error
        self.issued = self.failed = 0
        self.directory = ServiceDirectory(parse_manager_address(manager), "ln_play.services")
        self._conns: dict[tuple[str, int], _Connection] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True, name="ln_play services")
        self._thread.start()

    def _now(self, anchor: list[Any]) -> int:
        if not self.finished():
            anchor[:] = [self.position(), time.monotonic()]
            return int(anchor[0])
        return int(anchor[0] + (time.monotonic() - anchor[1]) * self.rate * 1e9)

    def _run(self) -> None:
        anchor: list[Any] = [self.position(), time.monotonic()]
        at = bisect.bisect_left(self.times, self.begin_ns)
        last = anchor[0]
        while not self._stop.is_set() and at < len(self.calls):
            now = self._now(anchor)
            if now < last:  # a seek back: issue the calls from there again
                at = bisect.bisect_left(self.times, now)
            last = now
            while at < len(self.calls) and self.times[at] <= now:
                self._issue(self.calls[at].call)
                at += 1
            self._stop.wait(TICK)

    def _issue(self, call: ServiceCall) -> None:
        key = (call.service, call.layout_hash)
        conn = self._conns.get(key)
        if conn is None:
            conn = self._conns[key] = _Connection(self.directory, *key)
        why = conn.call(call.request)
        self.issued += 1
        if why is not None:
            self.failed += 1
            self.on_error(f"call of service '{call.service}' failed: {why}")

    def wait(self) -> None:
        """Until every call was issued (KeyboardInterrupt ends it early)."""
        while self._thread.is_alive():
            self._thread.join(0.1)

    def stop(self) -> None:
        self._stop.set()
        self._thread.join()
        for conn in self._conns.values():
            conn.close()
        self.directory.close()


def start(manager: str, args: Any, rec: Any, pb: Any, say: Callable[[str], None]
          ) -> ServiceReplay:
    """ln_play's replay of the recorded calls (args: rate, start) beside the Playback `pb`
    of the recording `rec` (play_cli.py)."""
    calls = recorded_calls(rec.readers)
    firsts = [t for t in (rec.first_ns, calls[0].time_ns if calls else None) if t is not None]
    begin = min(firsts, default=0) + int(args.start * 1e9)
    has_topics = rec.first_ns is not None and bool(pb.ports)

    def position() -> int:
        return int(pb.position()) if has_topics else begin

    def finished() -> bool:
        return not has_topics or pb.state == "finished"

    say(f"re-issuing {len(calls)} service calls")
    return ServiceReplay(manager, calls, begin, position, finished, args.rate, say)
