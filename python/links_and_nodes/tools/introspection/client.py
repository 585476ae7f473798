"""The libln side of live introspection (docs/introspection.md): message definitions loaded
from the manager's md search path, a subscriber that attaches to a topic without
disturbing it, and one service call with a request given as plain values.

The subscriber is an ordinary one in *latest* mode (one buffer): it holds a reader slot
like any subscriber but never makes a publisher wait (only queued subscribers can), and the
ring never grows for it.  It subscribes with the layout the manager reports for the topic,
so `topic hz`/`bw` need no md at all, and reads raw bytes that introspect.py decodes.  What
it falls behind on it skips; the sequence numbers show the gaps."""

from __future__ import annotations

import ctypes
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ln_generate import MdError, MdRegistry, MessageDef, default_md_dirs
from ln_generate.registry import COMMAND_LINE

from .values import IntrospectError

READ_SLICE = 0.1  # seconds of one blocking read: stop requests and Ctrl-C are seen this often


def md_error_text(exc: MdError) -> str:
    """The first problem of an MdError in one line (without the `<command line>` place)."""
    if not exc.diagnostics:
        return str(exc) or "invalid message definition"
    first = exc.diagnostics[0]
    text = first.message if first.loc.file == COMMAND_LINE else str(first)
    more = len(exc.diagnostics) - 1
    return text + (f" (and {more} more problem{'s' * (more > 1)})" if more else "")


_models: dict[tuple[str, tuple[str, ...]], MessageDef] = {}
_classes: dict[tuple[str, tuple[str, ...]], type] = {}
_lock = threading.Lock()


def search_path(manager_dirs: list[str]) -> list[Path]:
    """The manager's md directories first, then this process's own (built-in and
    LN_MESSAGE_DEFINITION_DIRS): mds resolve as in the manager's configuration."""
    return default_md_dirs(list(manager_dirs))


def load_md(name: str, manager_dirs: list[str]) -> MessageDef:
    """The model of md `name`; IntrospectError (one line) if it cannot be loaded."""
    key = (name, tuple(manager_dirs))
    with _lock:
        md = _models.get(key)
        if md is None:
            try:
                md = MdRegistry(search_path(manager_dirs)).load(name)
            except MdError as exc:
                raise IntrospectError(md_error_text(exc)) from None
            _models[key] = md
        return md


def md_class(name: str, manager_dirs: list[str]) -> type:
    """The ctypes class (links_and_nodes.md_types.LnStruct) of md `name`, built as
    md_loader builds it but from the manager's search path."""
    key = (name, tuple(manager_dirs))
    md = load_md(name, manager_dirs)
    with _lock:
        cls = _classes.get(key)
        if cls is None:
            from ln_generate.emit_python import emit

            source = emit([md], Path(f"<md {name}>"), "runtime")
            namespace: dict[str, Any] = {"__name__": f"links_and_nodes.md.{name}"}
            exec(compile(source, f"<md {name}>", "exec"), namespace)  # noqa: S102
            cls = namespace["MESSAGES"][name]
            _classes[key] = cls
        return cls


@dataclass(frozen=True)
class Sample:
    seq: int
    timestamp_ns: int  # publish time, CLOCK_REALTIME
    data: bytes


class TopicReader:
    """A latest-mode subscriber of `topic` with the given layout, for one thread; use as a
    context manager.  libln errors (refusals of the manager) raise LnError.  `buffers` > 1
    makes it a queued subscriber (ln_foxglove's queued channels)."""

    def __init__(self, address: str, client_name: str, topic: str, md_name: str,
                 layout_hash: int, message_size: int, buffers: int = 1) -> None:
        from ... import _clientlib as C
        from ..._client import client

        self._c = C
        self.client = client(client_name, address, reconnect=False)
        try:
            opts = C.PortOptions()
            C.ln_port_options_init(ctypes.byref(opts))
            opts.buffers = buffers  # 1, latest: never holds a publisher back
            opts.spin_us = 0  # mostly waits long: sleep at once instead of polling
            handle = ctypes.c_void_p()
            self.subscribed_ns = time.time_ns()
            C.ln_subscribe(self.client.handle, ctypes.byref(handle), topic.encode(),
                           md_name.encode(), layout_hash, message_size, ctypes.byref(opts))
        except BaseException:
            self.client.close()
            raise
        self._handle: int | None = handle.value
        self.size = message_size
        self._buf = ctypes.create_string_buffer(message_size)
        self._info = C.SampleInfo()

    def read(self, timeout: float = READ_SLICE) -> Sample | None:
        """The next sample, or None if none came within `timeout` (at most a slice)."""
        C = self._c
        rc = C.ln_read(self._handle, self._buf, self.size, min(timeout, READ_SLICE),
                       ctypes.byref(self._info))
        if rc in (C.LN_ETIMEOUT, C.LN_EAGAIN):
            return None
        if rc < 0:
            from ..._libln import error_from_code

            raise error_from_code(rc, C.last_error())
        return Sample(self._info.seq, self._info.timestamp_ns, self._buf.raw)

    def close(self) -> None:
        handle, self._handle = self._handle, None
        if handle is not None:
            try:
                self._c.ln_unsubscribe(handle)
            finally:
                self.client.close()

    def __enter__(self) -> TopicReader:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def call_service(address: str, client_name: str, name: str, cls: Any, request: dict[str, Any],
                 timeout: float) -> dict[str, Any]:
    """Call service `name` of md class `cls` (a service LnStruct) once with `request` (values
    LnStruct.update takes); the response as plain values.  LnError for every failure (an
    error response is LnServiceError with the provider's text)."""
    from ... import _clientlib as C
    from ..._client import client
    from ...md_types import LnStruct

    parts = {member: elem for member, _kind, elem, _count in cls._ln_specs_}
    req: LnStruct = parts["req"]()
    req.update(request)
    raw: LnStruct = parts["resp"]()
    with client(client_name, address, reconnect=False) as clnt:
        handle = ctypes.c_void_p()
        C.ln_get_service(clnt.handle, ctypes.byref(handle), name.encode(),
                         cls.MD_NAME.encode(), cls.LAYOUT_HASH, cls.SIGNATURE.encode())
        try:
            C.ln_service_call(handle, ctypes.byref(req), ctypes.byref(raw), float(timeout))
            return raw.to_dict()  # copies out of libln's memory before it may go
        finally:
            C.ln_service_release(handle)
