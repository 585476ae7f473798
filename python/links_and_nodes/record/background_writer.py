"""An McapWriter that compresses, checksums and writes its chunks on a thread of its own, so
ln_record's reader threads only frame samples: a full chunk is sealed (a new one opens at
once) and handed to the writer thread, at most IN_FLIGHT of them at a time (then the next
flush waits for the oldest: memory stays bounded at a few chunks).  zlib's CRC, the
compressors and the write release the GIL, so on two cores the chunk work runs beside the
framing.  Records reach the file in the order they were made: everything that writes
directly (a new channel, a copied chunk, close) first waits for the chunks in flight.  A
failure of the writer thread (a full disk) is raised by the next write, flush or close."""

from __future__ import annotations

from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any

from ..mcap_chunk import RawChunk
from ..mcap_format import McapWriter

IN_FLIGHT = 2  # sealed chunks queued for or in the writer thread


class BackgroundMcapWriter(McapWriter):
    """McapWriter with its chunk output on a writer thread (see the module).  Like
    McapWriter, not thread-safe: callers serialize; `offset`, `message_count` and
    `chunk_count` count the chunks written so far, `pending` also those in flight."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="mcap writer")
        self._flying: deque[tuple[Future[None], int]] = deque()
        self._flying_bytes = 0  # raw bytes of the chunks in _flying (pending, per write)
        super().__init__(*args, **kwargs)

    @property
    def pending(self) -> int:
        """Bytes of messages not in the file yet: the open chunk and those in flight."""
        return len(self._chunk) + self._flying_bytes

    def flush(self) -> None:
        """Seal the open chunk and hand it to the writer thread (returns before it is in the
        file; close() or drain() wait for that)."""
        self._reap()
        sealed = self._seal()
        if sealed is None:
            return
        while len(self._flying) >= IN_FLIGHT:
            self._land()
        self._flying.append((self._pool.submit(self._finish_chunk, sealed), len(sealed.raw)))
        self._flying_bytes += len(sealed.raw)

    def drain(self) -> None:
        """Wait until every sealed chunk is in the file; raise the writer thread's error."""
        while self._flying:
            self._land()

    def _reap(self) -> None:
        """Forget the chunks already written; raise the error of one that failed."""
        while self._flying and self._flying[0][0].done():
            self._land()

    def _land(self) -> None:
        """Wait for the oldest chunk in flight to be written; raise its error."""
        future, size = self._flying.popleft()
        self._flying_bytes -= size
        future.result()

    def add_channel(self, topic: str, **kwargs: Any) -> int:
        self.drain()
        return super().add_channel(topic, **kwargs)

    def copy_chunk(self, chunk: RawChunk) -> None:
        self.flush()
        self.drain()
        super().copy_chunk(chunk)

    def close(self) -> None:
        if self._fd is None:
            return
        try:
            self.flush()
            self.drain()
        except BaseException:
            self._abandon()
            raise
        super().close()

    def _abandon(self) -> None:
        for future, _ in self._flying:
            future.cancel()
        self._pool.shutdown(wait=True)
        self._flying.clear()
        self._flying_bytes = 0
        super()._abandon()
