"""Support code of the daemon's ring and forwarding tests: libln ring taps through ctypes
(to write samples into rings the daemon made and read them out of rings it fills),
segment sizes in /dev/shm and removing a test instance's segments."""

from __future__ import annotations

import ctypes
import os
from pathlib import Path

from links_and_nodes import _adminlib
from links_and_nodes.errors import LnError
from links_and_nodes.naming import sanitize_instance


class Tap:
    """A libln ring tap (LN_TAP_EVERY): reads or injects samples of `message_size` bytes.
    libln's failures raise its LnError classes."""

    def __init__(self, name: str, layout_hash: int, message_size: int) -> None:
        self.size = message_size
        self._handle = ctypes.c_void_p()
        _adminlib.ln_ring_tap_open(ctypes.byref(self._handle), name.encode(), layout_hash,
                                   message_size, _adminlib.LN_TAP_EVERY)

    def close(self) -> None:
        if self._handle:
            _adminlib.ln_ring_tap_close(self._handle)
            self._handle = ctypes.c_void_p()

    def __enter__(self) -> Tap:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def inject(self, data: bytes, seq: int, timestamp_ns: int = 0) -> None:
        buf = ctypes.create_string_buffer(data.ljust(self.size, b"\0"), self.size)
        _adminlib.ln_ring_tap_inject(self._handle, buf, seq, timestamp_ns)

    def read(self, timeout: float) -> tuple[int, bytes] | None:
        """(seq, data) of the next sample, None if none came within `timeout` seconds."""
        buf = ctypes.create_string_buffer(self.size)
        info = _adminlib.SampleInfo()
        try:
            _adminlib.ln_ring_tap_read(self._handle, buf, ctypes.byref(info), timeout)
        except LnError as exc:
            if exc.name == "ETIMEOUT":
                return None
            raise
        return int(info.seq), buf.raw

    def write_seq(self) -> int:
        return int(_adminlib.ln_ring_tap_write_seq(self._handle))


def segment_size(name: str) -> int | None:
    """Bytes of segment `name` in /dev/shm, None if there is none."""
    try:
        return os.stat(Path("/dev/shm") / name.lstrip("/")).st_size
    except FileNotFoundError:
        return None


def ring_size(message_size: int, slots: int) -> int:
    return int(_adminlib.ln_ring_segment_size(message_size, slots))


def prefix(instance: str) -> str:
    return f"/ln.{sanitize_instance(instance)}."


def segments_of(instance: str) -> list[str]:
    start = prefix(instance)[1:]
    return sorted("/" + n for n in os.listdir("/dev/shm") if n.startswith(start))


def purge(instance: str) -> None:
    """Remove whatever segments a test of `instance` left behind."""
    _adminlib.ln_ring_admin_purge_instance(sanitize_instance(instance).encode())
