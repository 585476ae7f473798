"""The native core of ln_zenoh (ln_zenoh_core/, Rust): ctypes declarations of its C ABI and
the objects the bridge uses when it is found (docs/zenoh.md "The native core").

With the core the bridge's Zenoh session lives in it and the samples of topics never touch
Python: `Core` opens that session from the bridge's configuration plus a Unix socket in a
private directory, and the Python session connects to that socket as a client (Zenoh peers
route for their clients), so services, mds, liveliness and ROS 2 go on as before.  `OutTopic`
and `InRule` are the core's halves of outbound.py's and inbound.py's topics.

The library is found as libln's are (_native.py): $LN_ZENOH_CORE (a file or a directory),
build/release/ln_zenoh_core/ of the checkout, `links_and_nodes/` beside the libln.so.1 that was
loaded (where `scons install` puts it), the system loader.  A library is used only if it
agrees with this side on what is not in the signatures (`check_seam`): the counters' order
(the core's lnz_counter_names against stats.TopicStats) and the libln function table, which
is built here from the core's list (lnz_libln_functions).
"""

from __future__ import annotations

import ctypes
import json
import os
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import fields
from pathlib import Path
from typing import Any

from .. import _native
from .stats import TopicStats

SONAME = "libln_zenoh_core.so"
ENV = "LN_ZENOH_CORE"
ERR_SIZE = 1024
DIR_PREFIX = "ln_zenoh."  # the socket directory: <tmp>/ln_zenoh.<pid>.<random>/session.sock

c_char_p, c_double, c_int, c_size_t, c_uint64, c_void_p = (
    ctypes.c_char_p, ctypes.c_double, ctypes.c_int, ctypes.c_size_t, ctypes.c_uint64,
    ctypes.c_void_p)

LOG_FN = ctypes.CFUNCTYPE(None, c_void_p, c_char_p)
MATCH_FN = ctypes.CFUNCTYPE(None, c_void_p, c_int)
SAMPLE_FN = ctypes.CFUNCTYPE(None, c_void_p, ctypes.POINTER(ctypes.c_ubyte), c_size_t,
                             ctypes.POINTER(ctypes.c_ubyte), c_size_t,
                             ctypes.POINTER(ctypes.c_ubyte), ctypes.c_ssize_t)

# The counters the core adds to: the numbers of stats.TopicStats, in their order there
# (the core's counters.rs must list them alike: check_seam).
COUNTER_FIELDS = tuple(f.name for f in fields(TopicStats) if f.type in (int, "int"))


class Counters(ctypes.Structure):
    _fields_ = [(name, c_uint64) for name in COUNTER_FIELDS]


class CoreUnavailable(RuntimeError):
    """The core library cannot be loaded; `refused` when one was found but does not match
    this bridge (built from other sources)."""

    def __init__(self, why: str, refused: bool = False) -> None:
        super().__init__(why)
        self.refused = refused


class CoreError(RuntimeError):
    """A call of the core failed; the text says why."""


_lib: ctypes.CDLL | None = None
_why_not: CoreUnavailable | None = None
# Callbacks handed to the core are never freed: one the core is still running when its object
# closes (Zenoh may finish a delivery after an undeclare) must stay callable.  A few per
# topic, and topics are closed only when the bridge stops.
_RETIRED: list[Any] = []


def _candidates() -> list[str]:
    found = list(_native.candidates(SONAME, ENV, "ln_zenoh_core"))
    if not os.environ.get(ENV):
        try:
            from .. import _libln

            beside = _native.file_of(_libln.lib, "ln_version").parent / "links_and_nodes"
            found.insert(len(found) - 1, str(beside / SONAME))
        except Exception:  # noqa: BLE001 - libln itself missing: said when it is used
            pass
    return found


def load_core() -> ctypes.CDLL:
    """The loaded core; CoreUnavailable naming every place that was tried."""
    global _lib, _why_not
    if _lib is not None:
        return _lib
    if _why_not is not None:
        raise _why_not
    failures = []
    refused = False
    for candidate in _candidates():
        try:
            lib = ctypes.CDLL(candidate)
        except OSError as exc:
            failures.append(f"{candidate}: {exc}")
            continue
        try:
            check_seam(lib)
        except CoreUnavailable as exc:
            failures.append(f"{candidate}: {exc}")
            refused = True
            continue
        _declare_all(lib)
        _lib = lib
        return lib
    _why_not = CoreUnavailable("; ".join(failures) or "nowhere to look", refused)
    raise _why_not


def _names(lib: ctypes.CDLL, function: str) -> list[str]:
    """The space-separated names a core's `function` returns; CoreUnavailable if it has none."""
    try:
        fn = getattr(lib, function)
    except AttributeError:
        raise CoreUnavailable(f"it has no {function}: built from older sources, rebuild it "
                              "(scons)") from None
    fn.restype, fn.argtypes = c_char_p, []
    return fn().decode().split()


def check_seam(lib: ctypes.CDLL) -> None:
    """CoreUnavailable unless the core counts what stats.TopicStats counts, in its order, and
    names the libln functions it takes (ln_fns checks that libln has them)."""
    theirs = _names(lib, "lnz_counter_names")
    if theirs != list(COUNTER_FIELDS):
        raise CoreUnavailable(
            "its counters differ from this bridge's (ln_zenoh_core/src/counters.rs against "
            f"zenoh_bridge/stats.py TopicStats): core {' '.join(theirs)}; bridge "
            f"{' '.join(COUNTER_FIELDS)}: rebuild the core from these sources (scons)")
    if not _names(lib, "lnz_libln_functions"):
        raise CoreUnavailable("its libln function table is empty")


def _declare_all(lib: ctypes.CDLL) -> None:
    d = _native.declare
    d(lib, "lnz_open", c_void_p, [c_char_p, c_void_p, LOG_FN, c_void_p, c_char_p, c_size_t])
    d(lib, "lnz_zid", c_int, [c_void_p, c_char_p, c_size_t])
    d(lib, "lnz_close", None, [c_void_p])
    d(lib, "lnz_out_open", c_void_p, [c_void_p, c_char_p, c_char_p, c_void_p, c_size_t, c_char_p,
                                      c_uint64, c_int, c_double, ctypes.POINTER(Counters),
                                      c_char_p, MATCH_FN, c_void_p, c_char_p, c_size_t])
    d(lib, "lnz_out_matching", c_int, [c_void_p])
    d(lib, "lnz_out_close", None, [c_void_p])
    d(lib, "lnz_in_open", c_void_p, [c_void_p, c_char_p, c_char_p, SAMPLE_FN, c_void_p,
                                     c_char_p, c_size_t])
    d(lib, "lnz_in_batch", c_int, [c_void_p, c_int, c_char_p, c_size_t])
    d(lib, "lnz_in_bad_batches", c_uint64, [c_void_p])
    d(lib, "lnz_in_ready", c_int, [c_void_p, c_char_p, c_void_p, c_void_p, c_size_t,
                                   c_char_p, c_uint64, c_double, c_int,
                                   ctypes.POINTER(Counters), c_char_p, c_char_p, c_size_t])
    d(lib, "lnz_in_offer", c_int, [c_void_p, c_char_p, c_char_p, c_size_t, c_char_p,
                                   ctypes.c_ssize_t])
    d(lib, "lnz_in_forget", None, [c_void_p, c_char_p])
    d(lib, "lnz_in_close", None, [c_void_p])


def ln_fns(lib: ctypes.CDLL, libln: Any) -> ctypes.Structure:
    """The libln function table lnz_open takes: `ln_<name>` of `libln` for each name of the
    core's lnz_libln_functions, in that order (ln_zenoh_core/src/libln.rs)."""
    names = _names(lib, "lnz_libln_functions")
    missing = [name for name in names if not hasattr(libln, f"ln_{name}")]
    if missing:
        raise CoreError(f"the native core needs libln functions this libln does not have: "
                        f"{', '.join('ln_' + n for n in missing)}")
    table = type("LnFns", (ctypes.Structure,), {"_fields_": [(n, c_void_p) for n in names]})
    return table(*(ctypes.cast(getattr(libln, f"ln_{n}"), c_void_p).value for n in names))


def _err() -> ctypes.Array[ctypes.c_char]:
    return ctypes.create_string_buffer(ERR_SIZE)


def _text(err: ctypes.Array[ctypes.c_char]) -> str:
    return err.value.decode("utf-8", "replace") or "unknown error"


def remove_stale_dirs() -> None:
    """Remove the socket directories of bridges that died without removing theirs."""
    for path in Path(tempfile.gettempdir()).glob(f"{DIR_PREFIX}*.*"):
        pid = path.name[len(DIR_PREFIX):].split(".", 1)[0]
        if not pid.isdigit() or not path.is_dir() or path.stat().st_uid != os.getuid():
            continue
        try:
            os.kill(int(pid), 0)
        except ProcessLookupError:
            shutil.rmtree(path, ignore_errors=True)
        except PermissionError:  # alive, another user's
            pass


class Core:
    """The core's Zenoh session.  `client_config(zc)` turns the Python side's configuration
    into the one of a client of this session (peer mode), or leaves it (client mode: both
    sessions are clients of the same routers)."""

    def __init__(self, zenoh_config: Any, mode: str, say: Callable[[str], None]) -> None:
        self.lib = load_core()
        self.mode = mode
        self._say = say
        self._log = LOG_FN(lambda _ctx, text: say(text.decode("utf-8", "replace")))
        from .. import _libln

        self._fns = ln_fns(self.lib, _libln.lib)
        self._dir: str | None = None
        self.socket: str | None = None
        config = json.loads(str(zenoh_config))
        if mode == "peer":
            remove_stale_dirs()
            # 0700: only this user connects; the pid lets a later bridge remove it if this
            # process is killed before it can
            self._dir = tempfile.mkdtemp(prefix=f"{DIR_PREFIX}{os.getpid()}.")
            self.socket = os.path.join(self._dir, "session.sock")
            listen = config.setdefault("listen", {})
            endpoints = listen.get("endpoints") or []
            if isinstance(endpoints, dict):  # per-mode endpoints: {"peer": [...], ...}
                endpoints = endpoints.get("peer") or []
            listen["endpoints"] = [*endpoints, f"unixsock-stream/{self.socket}"]
        err = _err()
        handle = self.lib.lnz_open(json.dumps(config).encode(), ctypes.byref(self._fns),
                                   self._log, None, err, ERR_SIZE)
        if not handle:
            self._remove_dir()
            raise CoreError(_text(err))
        self.handle: int | None = handle

    def client_config(self, zc: Any) -> Any:
        """The Python session's configuration: a client of this session over its socket."""
        if self.socket is None:
            return zc
        zc.insert_json5("mode", '"client"')
        zc.insert_json5("connect/endpoints", json.dumps([f"unixsock-stream/{self.socket}"]))
        zc.insert_json5("listen/endpoints", "[]")
        zc.insert_json5("scouting/multicast/enabled", "false")
        return zc

    def zid(self) -> str:
        out = ctypes.create_string_buffer(128)
        self.lib.lnz_zid(self.handle, out, len(out))
        return out.value.decode()

    def out_topic(self, *, key: str, batch_key: str | None, port: Any, md_name: str,
                  layout_hash: int, queued: bool, rate: float | None, counters: Counters,
                  label: str, on_match: Callable[[bool], None]) -> OutTopic:
        return OutTopic(self, key, batch_key, port, md_name, layout_hash, queued, rate,
                        counters, label, on_match)

    def in_rule(self, key_expr: str, remote: str | None,
                on_sample: Callable[[str, bytes, bytes | None], None]) -> InRule:
        return InRule(self, key_expr, remote, on_sample)

    def close(self) -> None:
        handle, self.handle = self.handle, None
        if handle:
            self.lib.lnz_close(handle)
            _RETIRED.append(self._log)
        self._remove_dir()

    def _remove_dir(self) -> None:
        if self._dir is not None:
            shutil.rmtree(self._dir, ignore_errors=True)
            self._dir = None


class OutTopic:
    """The core's reader of one outbound topic: it reads `port` (a subscriber; not used by
    Python meanwhile) and puts the samples while a remote subscriber matches, and in batches
    on `batch_key` (None: not) while a bridge takes them."""

    def __init__(self, core: Core, key: str, batch_key: str | None, port: Any, md_name: str,
                 layout_hash: int, queued: bool, rate: float | None, counters: Counters,
                 label: str, on_match: Callable[[bool], None]) -> None:
        self.core = core
        self.counters = counters  # kept alive while the core writes to it
        self._match = MATCH_FN(lambda _ctx, matching: on_match(bool(matching)))
        err = _err()
        size = ctypes.sizeof(port.packet)
        handle = core.lib.lnz_out_open(core.handle, key.encode(),
                                       batch_key.encode() if batch_key else None,
                                       port.handle, size, md_name.encode(), layout_hash,
                                       int(queued),
                                       float(rate or 0.0), ctypes.byref(counters),
                                       label.encode(), self._match, None, err, ERR_SIZE)
        if not handle:
            raise CoreError(_text(err))
        self.handle: int | None = handle

    @property
    def matching(self) -> bool:
        return bool(self.handle) and bool(self.core.lib.lnz_out_matching(self.handle))

    def close(self) -> None:
        """Stops reading; the port may be closed once this returns."""
        handle, self.handle = self.handle, None
        if handle:
            self.core.lib.lnz_out_close(handle)
            _RETIRED.append(self._match)


class InRule:
    """The core's subscription of one inbound rule.  Samples of keys not handed over come to
    `on_sample(key, payload, attachment)` in Zenoh's thread; `ready` hands a key over.
    `set_batch` takes the batches of the bridge with prefix `remote` instead."""

    def __init__(self, core: Core, key_expr: str, remote: str | None,
                 on_sample: Callable[[str, bytes, bytes | None], None]) -> None:
        self.core = core
        self._keep: dict[str, Counters] = {}  # counters of handed-over keys, kept alive

        def deliver(_ctx: Any, key: Any, key_len: int, payload: Any, size: int, att: Any,
                    att_len: int) -> None:
            # An exception here is printed by ctypes (sys.unraisablehook) and goes no further.
            on_sample(ctypes.string_at(key, key_len).decode("utf-8", "replace"),
                      ctypes.string_at(payload, size),
                      ctypes.string_at(att, att_len) if att_len >= 0 else None)

        self._deliver = SAMPLE_FN(deliver)
        err = _err()
        handle = core.lib.lnz_in_open(core.handle, key_expr.encode(),
                                      remote.encode() if remote else None, self._deliver, None,
                                      err, ERR_SIZE)
        if not handle:
            raise CoreError(_text(err))
        self.handle: int | None = handle

    def ready(self, key: str, port: Any, wait_port: Any, md_name: str, layout_hash: int,
              rate: float | None, congested: bool, counters: Counters, label: str) -> None:
        """From now on the core checks and publishes the samples of `key` on `port`; a queued
        topic's first through `wait_port`, a publisher that waits for its subscribers
        (inbound.HOLD_S at most; not while `congested`), None for a latest one."""
        if not self.handle:
            return
        err = _err()
        self._keep[key] = counters
        if self.core.lib.lnz_in_ready(self.handle, key.encode(), port.handle,
                                      wait_port.handle if wait_port is not None else None,
                                      ctypes.sizeof(port.packet), md_name.encode(),
                                      layout_hash, float(rate or 0.0), int(congested),
                                      ctypes.byref(counters),
                                      label.encode(), err, ERR_SIZE) < 0:
            del self._keep[key]
            raise CoreError(_text(err))

    def set_batch(self, on: bool) -> None:
        """Subscribe to the remote bridge's batches instead of its per-topic samples, or back
        (CoreError if the subscription cannot be made)."""
        if not self.handle:
            return
        err = _err()
        if self.core.lib.lnz_in_batch(self.handle, int(on), err, ERR_SIZE) < 0:
            raise CoreError(_text(err))

    def bad_batches(self) -> int:
        """Malformed batches dropped for topics not handed over."""
        return int(self.core.lib.lnz_in_bad_batches(self.handle)) if self.handle else 0

    def offer(self, key: str, payload: bytes, attachment: bytes | None) -> bool:
        """Let the core handle a sample of the handed-over `key` that reached Python while
        it was handed over; False if `key` is not handed over."""
        if not self.handle:
            return False
        att_len = len(attachment) if attachment is not None else -1
        return self.core.lib.lnz_in_offer(self.handle, key.encode(), payload, len(payload),
                                          attachment, att_len) == 0

    def forget(self, key: str) -> None:
        """The core stops using the key's port and counters before this returns."""
        if self.handle and key in self._keep:
            self.core.lib.lnz_in_forget(self.handle, key.encode())
            del self._keep[key]

    def close(self) -> None:
        handle, self.handle = self.handle, None
        if handle:
            self.core.lib.lnz_in_close(handle)
            _RETIRED.append(self._deliver)
        self._keep.clear()
