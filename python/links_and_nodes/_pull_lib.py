"""Private ctypes layer over libln_pull, the pull-topic consumer (ln/pull.h, ln/pull_udp.h):
finds and loads the library the way _libln.py finds libln, mirrors the consumer's structs
field for field (checked against the library's own size), and declares each function once.
links_and_nodes.pull sits on top of this."""

from __future__ import annotations

import ctypes
import functools

from . import _native
from .errors import LibraryNotFoundError

SONAME = "libln_pull.so.1"
ENV_OVERRIDE = "LN_PULL_LIBRARY_PATH"  # a library file, or a directory holding it

MAX_WINDOW = 16  # LN_PULL_MAX_WINDOW
MAX_NAME = 96  # LN_PULL_MAX_NAME
# Hardenings (LN_PULL_*)
SLOT_OFFSET, SKIP_OLD, NACK_JUMP, SYNC_QUARTER, KARN = 1, 2, 4, 8, 16
EV_TIMEOUT, EV_NACK, EV_SYNC = 1, 2, 3


lib = _native.load(SONAME, ENV_OVERRIDE, "libln_pull", "libln_pull")

SendFn = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.POINTER(ctypes.c_uint8),
                          ctypes.c_size_t)
DataFn = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_uint64,
                          ctypes.POINTER(ctypes.c_uint8), ctypes.c_size_t, ctypes.c_uint64)
EventFn = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_int, ctypes.c_uint64,
                           ctypes.c_uint32)


class Options(ctypes.Structure):
    _fields_ = [("t_min_ms", ctypes.c_uint32), ("t_max_ms", ctypes.c_uint32),
                ("window", ctypes.c_uint8), ("boot_after", ctypes.c_uint8),
                ("flags", ctypes.c_uint16), ("poll_ms", ctypes.c_uint32)]


class Stats(ctypes.Structure):
    _fields_ = [(name, ctypes.c_uint32) for name in
                ("interests", "syncs", "data", "timeouts", "nacks", "late", "bad",
                 "refreshes", "rejected")]


class Slot(ctypes.Structure):
    _fields_ = [("seq", ctypes.c_uint64), ("sent_ms", ctypes.c_uint32),
                ("nonce", ctypes.c_uint32)]


class Sub(ctypes.Structure):
    """struct ln_pull_sub; its fields are the core's, read here only for stats and t."""

    _fields_ = [("opt", Options), ("syncing", ctypes.c_uint8),
                ("timeouts_in_row", ctypes.c_uint8), ("window", ctypes.c_uint8),
                ("since_loss", ctypes.c_uint8), ("name_size", ctypes.c_uint16),
                ("t_ms", ctypes.c_uint32), ("sync_sent_ms", ctypes.c_uint32),
                ("sync_nonce", ctypes.c_uint32), ("period_ewma_us", ctypes.c_uint32),
                ("last_arrival_ms", ctypes.c_uint32), ("rng", ctypes.c_uint32),
                ("srtt_us", ctypes.c_uint32), ("send", SendFn), ("on_data", DataFn),
                ("on_event", EventFn), ("user", ctypes.c_void_p),
                ("delivered_seq", ctypes.c_uint64), ("next_seq", ctypes.c_uint64),
                ("latest_seq", ctypes.c_uint64), ("stats", Stats),
                ("slot_state", ctypes.c_uint8 * MAX_WINDOW), ("slots", Slot * MAX_WINDOW),
                ("name", ctypes.c_uint8 * MAX_NAME),
                ("key", ctypes.c_void_p), ("key_size", ctypes.c_size_t)]


_declare = functools.partial(_native.declare, lib)


ln_ndn_strerror = _declare("ln_ndn_strerror", ctypes.c_char_p, [ctypes.c_int])
ln_pull_options_naive = _declare("ln_pull_options_naive", None, [ctypes.POINTER(Options)])
ln_pull_options_hardened = _declare("ln_pull_options_hardened", None,
                                    [ctypes.POINTER(Options), ctypes.c_uint32])
ln_pull_start = _declare("ln_pull_start", ctypes.c_int, [
    ctypes.POINTER(Sub), ctypes.c_char_p, ctypes.POINTER(Options), SendFn, DataFn, EventFn,
    ctypes.c_void_p, ctypes.c_uint32, ctypes.c_uint32])
ln_pull_receive = _declare("ln_pull_receive", ctypes.c_int, [
    ctypes.POINTER(Sub), ctypes.c_char_p, ctypes.c_size_t, ctypes.c_uint32])
ln_pull_poll = _declare("ln_pull_poll", ctypes.c_uint32, [ctypes.POINTER(Sub), ctypes.c_uint32])
ln_pull_udp_now_ms = _declare("ln_pull_udp_now_ms", ctypes.c_uint32, [])
# The glue's send function: sends on the fd that `user` points to, without a trip through
# Python for every Interest.
udp_send = ctypes.cast(lib.ln_pull_udp_send, SendFn)


def strerror(code: int) -> str:
    text = ln_ndn_strerror(code)
    return text.decode() if text else f"error {code}"


def _check_size() -> None:
    """The mirror must be exactly the C struct (the core writes all of it)."""
    size_of = getattr(lib, "ln_pull_sub_size", None)
    if size_of is None:
        return
    size_of.restype, size_of.argtypes = ctypes.c_size_t, []
    if size_of() != ctypes.sizeof(Sub):
        raise LibraryNotFoundError(
            f"libln_pull's ln_pull_sub is {size_of()} bytes, this package's mirror "
            f"{ctypes.sizeof(Sub)}: the library and the package do not belong together")


_check_size()
