"""The recording loop of ln_record: one queued subscription and one reader thread per topic.

Each thread blocks in its port's read (libln releases the GIL meanwhile), encodes every
sample in the recording's encoding (record/encodings.py; outside the lock, so topics encode
side by side) and appends it, with its sequence number and publish time from the read's
sample info, to the shared SplitWriter under one lock.  On stop each thread first drains what its queue holds, so a
sample published before the stop is recorded.  The overruns a read reports are the samples the ring dropped
before the recorder got to them: they are counted per topic.
"""

from __future__ import annotations

import ctypes
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from .. import md_loader
from ..mcap_format import md_schema_text
from .defaults import DEFAULT_BUFFER_MEMORY, DEFAULT_ENCODING, MAX_BUFFERS
from .encodings import EncodingError, channel_encoder
from .split_writer import SplitWriter

READ_SLICE = 0.2  # seconds a reader thread waits before it looks at the stop flag


def buffers_for(message_size: int, buffers: int | None, memory: int) -> int:
    """Queued buffers of a subscription: `buffers` if given, else as many as `memory` bytes
    hold, from 2 to libln's limit."""
    if buffers:
        return buffers
    return max(2, min(MAX_BUFFERS, memory // max(1, message_size)))


@dataclass
class Recorded:
    """One topic being recorded."""

    topic: str
    md_name: str
    channel: int
    buffers: int
    port: Any  # links_and_nodes subscriber
    encode: Callable[[Any], Any]  # the sample's ln bytes -> the bytes stored
    samples: int = 0
    drops: int = 0
    thread: threading.Thread | None = None


class Recorder:
    """Records topics of `client` into `out` until stop()."""

    def __init__(self, client: Any, out: SplitWriter, buffers: int | None = None,
                 buffer_memory: int = DEFAULT_BUFFER_MEMORY,
                 encoding: str = DEFAULT_ENCODING) -> None:
        self.client = client
        self.encoding = encoding
        self.out = out
        self.buffers = buffers
        self.buffer_memory = buffer_memory
        self.lock = threading.Lock()  # around `out` and the counters
        self.topics: dict[str, Recorded] = {}
        self.samples = 0
        self.bytes = 0
        self.error: str | None = None  # why recording failed (a write error), if it did
        self._stop = threading.Event()

    @property
    def drops(self) -> int:
        return sum(rec.drops for rec in self.topics.values())

    @property
    def stopping(self) -> bool:
        return self._stop.is_set()

    def add(self, topic: str, md_name: str) -> str | None:
        """Start recording `topic`; None, or why it cannot be recorded."""
        try:
            cls = md_loader.message_class(md_name)
            text = md_schema_text(md_name)
        except Exception as exc:  # noqa: BLE001 - MdError and file errors: a reason to show
            return f"its md '{md_name}' cannot be loaded here: {exc}"
        if cls._ln_has_dynamic_:
            return (f"its md '{md_name}' has dynamic fields: a sample holds their pointers, "
                    "not their data")
        size = ctypes.sizeof(cls)
        try:
            encoder = channel_encoder(self.encoding, md_name, text, cls.LAYOUT_HASH, size)
        except EncodingError as exc:
            return f"encoding {self.encoding} cannot take it: {exc}"
        buffers = buffers_for(size, self.buffers, self.buffer_memory)
        try:
            port = self.client.subscribe(topic, md_name, buffers=buffers)
        except Exception as exc:  # noqa: BLE001 - LnError and friends carry libln's text
            return str(exc)
        with self.lock:
            try:
                channel = self.out.add_channel(topic, encoder)
            except OSError as exc:
                port.close()
                self._fail(f"cannot write {self.out.writer.path}: {exc}")
                return self.error
        rec = Recorded(topic, md_name, channel, buffers, port, encoder.encode)
        rec.thread = threading.Thread(target=self._run, args=(rec,), daemon=True,
                                      name=f"ln_record {topic}")
        self.topics[topic] = rec
        rec.thread.start()
        return None

    def _run(self, rec: Recorded) -> None:
        port = rec.port
        info = port.info
        size = ctypes.sizeof(port.packet)
        data = memoryview(port.packet).cast("B")  # read() fills this packet every time
        read: Callable[..., Any] = port.read
        lock, write, stop, encode = self.lock, self.out.write, self._stop, rec.encode
        left = -1  # after stop: how many queued samples may still be drained
        try:
            while left:
                if stop.is_set() and left < 0:
                    if self.error is not None:
                        return
                    left = rec.buffers  # what the queue held when the stop came, at most
                if read(timeout=0 if left > 0 else READ_SLICE) is None:
                    if left > 0:
                        return
                    continue
                if left > 0:
                    left -= 1
                payload = encode(data)
                with lock:
                    write(rec.channel, info.seq, info.timestamp_ns, payload)
                    self.samples += 1
                    self.bytes += size
                rec.samples += 1
                rec.drops += info.overruns
        except OSError as exc:
            self._fail(f"cannot write {self.out.writer.path}: {exc}")
        except Exception as exc:  # noqa: BLE001 - ends this topic, reported by the CLI
            self._fail(f"recording '{rec.topic}' failed: {type(exc).__name__}: {exc}")

    def _fail(self, reason: str) -> None:
        if self.error is None:
            self.error = reason
        self._stop.set()

    def flush(self) -> None:
        """Write the open chunk (so that a kill loses at most what came since)."""
        with self.lock:
            if self.error is None:
                try:
                    self.out.flush()
                except OSError as exc:
                    self.error = f"cannot write {self.out.writer.path}: {exc}"
                    self._stop.set()

    def stop(self) -> None:
        """End every reader thread and take the ports' final overrun counts."""
        self._stop.set()
        for rec in self.topics.values():
            if rec.thread is not None:
                rec.thread.join()
            try:
                rec.drops = max(rec.drops, rec.port.overruns)
            except ValueError:  # port closed
                pass
