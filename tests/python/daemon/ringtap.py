"""Support code of the daemon's ring and forwarding tests: libln ring taps through ctypes
(to write samples into rings the daemon made and read them out of rings it fills),
segment sizes in /dev/shm and removing a test instance's segments."""

from __future__ import annotations

import ctypes
import os
from pathlib import Path

from links_and_nodes import _libln
from links_and_nodes.manager.segments import sanitize_instance

TAP_EVERY = 0
TAP_NEWEST = 1
_OK, _ETIMEOUT = 0, -3


class _SampleInfo(ctypes.Structure):
    _fields_ = [("seq", ctypes.c_uint64), ("timestamp_ns", ctypes.c_int64),
                ("overruns", ctypes.c_uint64)]


_lib = _libln.lib
_lib.ln_ring_tap_open.restype = ctypes.c_int
_lib.ln_ring_tap_open.argtypes = [ctypes.POINTER(ctypes.c_void_p), ctypes.c_char_p,
                                  ctypes.c_uint64, ctypes.c_uint64, ctypes.c_uint]
_lib.ln_ring_tap_close.restype = None
_lib.ln_ring_tap_close.argtypes = [ctypes.c_void_p]
_lib.ln_ring_tap_read.restype = ctypes.c_int
_lib.ln_ring_tap_read.argtypes = [ctypes.c_void_p, ctypes.c_void_p,
                                  ctypes.POINTER(_SampleInfo), ctypes.c_double]
_lib.ln_ring_tap_inject.restype = ctypes.c_int
_lib.ln_ring_tap_inject.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_uint64,
                                    ctypes.c_int64]
_lib.ln_ring_tap_write_seq.restype = ctypes.c_uint64
_lib.ln_ring_tap_write_seq.argtypes = [ctypes.c_void_p]
_lib.ln_last_error.restype = ctypes.c_char_p
_lib.ln_last_error.argtypes = []


class TapError(Exception):
    def __init__(self, what: str, code: int) -> None:
        super().__init__(f"{what}: {code}: {_lib.ln_last_error().decode(errors='replace')}")
        self.code = code


class Tap:
    """A libln ring tap: reads or injects samples of `message_size` bytes."""

    def __init__(self, name: str, layout_hash: int, message_size: int,
                 mode: int = TAP_EVERY) -> None:
        self.size = message_size
        self._handle = ctypes.c_void_p()
        rc = _lib.ln_ring_tap_open(ctypes.byref(self._handle), name.encode(), layout_hash,
                                   message_size, mode)
        if rc != _OK:
            raise TapError(f"ln_ring_tap_open({name})", rc)

    def close(self) -> None:
        if self._handle:
            _lib.ln_ring_tap_close(self._handle)
            self._handle = ctypes.c_void_p()

    def __enter__(self) -> Tap:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def inject(self, data: bytes, seq: int, timestamp_ns: int = 0) -> None:
        buf = ctypes.create_string_buffer(data.ljust(self.size, b"\0"), self.size)
        rc = _lib.ln_ring_tap_inject(self._handle, buf, seq, timestamp_ns)
        if rc != _OK:
            raise TapError(f"ln_ring_tap_inject(seq {seq})", rc)

    def read(self, timeout: float) -> tuple[int, bytes] | None:
        """(seq, data) of the next sample, None if none came within `timeout` seconds."""
        buf = ctypes.create_string_buffer(self.size)
        info = _SampleInfo()
        rc = _lib.ln_ring_tap_read(self._handle, buf, ctypes.byref(info), timeout)
        if rc == _ETIMEOUT:
            return None
        if rc != _OK:
            raise TapError("ln_ring_tap_read", rc)
        return int(info.seq), buf.raw

    def write_seq(self) -> int:
        return int(_lib.ln_ring_tap_write_seq(self._handle))


def segment_size(name: str) -> int | None:
    """Bytes of segment `name` in /dev/shm, None if there is none."""
    try:
        return os.stat(Path("/dev/shm") / name.lstrip("/")).st_size
    except FileNotFoundError:
        return None


def ring_size(message_size: int, slots: int) -> int:
    return int(_libln.ln_ring_segment_size(message_size, slots))


def prefix(instance: str) -> str:
    return f"/ln.{sanitize_instance(instance)}."


def segments_of(instance: str) -> list[str]:
    start = prefix(instance)[1:]
    return sorted("/" + n for n in os.listdir("/dev/shm") if n.startswith(start))


def purge(instance: str) -> None:
    """Remove whatever segments a test of `instance` left behind."""
    _libln.ln_ring_admin_purge_instance(sanitize_instance(instance).encode())
