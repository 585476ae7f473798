"""The Python event API (docs/events.md): handlers (`event_handler`, made by
`client.connect_event`) and callers (`event`, made by `client.get_event`; `client.call_event`
for a single call).

    h = clnt.connect_event("robot.faults", "robot/fault_event", on_fault, min_severity=2)
    n = clnt.call_event("robot.faults", "robot/fault_event", severity=3, code=7, text="hot")

libln finds the handlers, encodes, sends, decodes and checks everything; this module holds
the handles and the ctypes callbacks and copies decoded data out of libln's memory, so that
no Python object points into memory libln may free.
"""

from __future__ import annotations

import ctypes
import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from . import _eventlib as E
from ._handles import CallerHandle, HandlerHandle, handling, keep_for_wait
from ._libln import ERROR_CLASSES, ERRORS_BY_CODE
from ._services import _name_arg, _timeout, error_text
from .md_loader import message_class
from .md_types import LnStruct, own_dynamic_data

if TYPE_CHECKING:
    from ._client import client

__all__ = ["EventResult", "event", "event_handler"]

_log = logging.getLogger("links_and_nodes.events")

Handler = Callable[[Any], Any]
Filter = Callable[[Any], bool]


def _sections(md_name: str) -> tuple[type[LnStruct], type[LnStruct], type[LnStruct]]:
    """The event class of `md_name` and its connect and call classes."""
    cls = message_class(md_name)
    if getattr(cls, "KIND", None) != "event":
        raise ERROR_CLASSES["LnMdError"](
            f"'{md_name}' is not an event definition (it has no connect/call sections)")
    parts = {name: elem for name, _kind, elem, _count in cls._ln_specs_}
    return cls, parts["connect"], parts["call"]


def _struct(cls: type[LnStruct], value: Any, fields: dict[str, Any], what: str) -> Any:
    """A struct of `cls` from a struct of it, a dict and/or keyword fields."""
    if isinstance(value, cls):
        if fields:
            raise TypeError(f"{what}: give a struct or fields, not both")
        return value
    if value is not None and not isinstance(value, dict):
        raise TypeError(f"{what}: expected a {cls.__name__} struct or a dict of its fields, "
                        f"not {type(value).__name__}")
    obj = cls()
    try:
        obj.update({**(value or {}), **fields})
    except KeyError:
        names = ", ".join(name for name, *_ in cls._ln_specs_) or "(none)"
        unknown = sorted(set(value or {}) | set(fields)
                         - {name for name, *_ in cls._ln_specs_})
        raise TypeError(f"{what}: no field {', '.join(map(repr, unknown))}; its fields: "
                        f"{names}") from None
    return obj


def _copy(cls: type[LnStruct], address: int) -> Any:
    """A struct of `cls` owning a copy of the one at `address` (dynamic data included)."""
    obj = cls()
    ctypes.memmove(ctypes.addressof(obj), address, ctypes.sizeof(obj))
    own_dynamic_data(obj)
    return obj


# ---- handlers ----------------------------------------------------------------------------
class event_handler(HandlerHandle):  # noqa: N801 - like provided_service
    """A handler connected to event `name`; made by `client.connect_event`.

    `handler(call)` runs once per call of the event, in the thread that handles its group
    (client.wait_and_handle_service_group_requests, or a thread pool), with the call struct
    (Python's own copy).  It returns None (the call is delivered without a reply), a call
    struct or a dict of call fields (the reply), or raises (the caller's result for this
    handler is LnServiceError with "TypeName: message")."""

    def __init__(self, clnt: client, name: str, md_name: str, handler: Handler,
                 connect: Any = None, group: str | None = None,
                 connect_fields: dict[str, Any] | None = None) -> None:
        super().__init__(clnt, name, md_name, group)
        self.handler = handler
        self.event_class, self.connect_class, self.call_class = _sections(md_name)
        self.connect = _struct(self.connect_class, connect, connect_fields or {},
                               f"event '{name}' ({md_name} connect)")
        # libln calls this from whichever thread handles the group, until disconnected or
        # the client is destroyed.
        self._callback = E.EVENT_HANDLER(self._on_call)
        handle = ctypes.c_void_p()
        E.ln_event_connect(clnt.handle, ctypes.byref(handle), name.encode(), md_name.encode(),
                           self.event_class.LAYOUT_HASH, self.event_class.SIGNATURE.encode(),
                           ctypes.byref(self.connect), self._callback, None, _name_arg(group))
        self._handle = handle.value
        #: the handler's service name, "ln_event/EVENT/CLIENT.N"
        self.service_name: str = E.ln_event_handler_name(handle).decode()

    def _on_call(self, _clnt: int | None, req: int | None, _user_data: int | None) -> int:
        # Runs under the GIL, called by libln; must never raise into ctypes.
        with handling(self.client):
            try:
                call = self.call_class()
                E.ln_event_request_get_data(req, ctypes.byref(call))
                own_dynamic_data(call)
                result = self.handler(call)
                if result is not None:
                    reply = _struct(self.call_class, result, {},
                                    f"event '{self.name}': the handler's reply")
                    E.ln_event_request_reply(req, ctypes.byref(reply))
            except BaseException as exc:  # noqa: BLE001 - becomes the error answer
                self._failed(req, exc)
        return 0

    def _failed(self, req: int | None, exc: BaseException) -> None:
        text = error_text(exc)
        _log.info("event '%s': handler failed: %s", self.name, text, exc_info=exc)
        try:
            E.ln_event_request_reply_error(req, text.encode("utf-8", "replace"))
        except Exception:  # noqa: BLE001 - answered already, or nothing left to tell
            _log.info("event '%s': could not answer with an error", self.name, exc_info=True)
        keep_for_wait(exc, f"event '{self.name}'")

    _what = "handler of event"

    def _release(self, handle: int) -> None:
        E.ln_event_disconnect(handle)


# ---- callers -----------------------------------------------------------------------------
@dataclass
class EventResult:
    """What one handler did with a call."""

    handler: str  # its service name
    client: str  # the client that connected it
    code: int  # 0: it received the call
    error: str  # why not ("" if it did)
    connect: Any  # its connect struct
    reply: Any  # its reply (a call struct), None without one

    @property
    def ok(self) -> bool:
        return self.code == 0

    @property
    def error_name(self) -> str:
        """"OK" or the LN_E* table name ("ESERVICE", "ECONNECTION", ...)."""
        cls = ERRORS_BY_CODE.get(self.code)
        return "OK" if self.code == 0 else cls.name if cls is not None else str(self.code)


class event(CallerHandle):  # noqa: N801 - like service
    """A caller's handle of event `name`; made by `client.get_event`.

    `call(fields, timeout=None, **fields)` sends a call struct to every handler connected
    at that moment (those `filter(connect)` accepts, if set) and returns how many received
    it; `results` then holds an EventResult per handler it went to.  The connections to the
    handlers stay open between calls.  Calls on one handle are serialized."""

    _what = "event"

    def __init__(self, clnt: client, name: str, md_name: str) -> None:
        super().__init__(clnt, name, md_name)
        self.event_class, self.connect_class, self.call_class = _sections(md_name)
        self.results: list[EventResult] = []
        self._filter: Filter | None = None
        self._filter_error: BaseException | None = None
        self._filter_callback = E.EVENT_FILTER(self._on_filter)
        handle = ctypes.c_void_p()
        E.ln_get_event(clnt.handle, ctypes.byref(handle), name.encode(), md_name.encode(),
                       self.event_class.LAYOUT_HASH, self.event_class.SIGNATURE.encode())
        self._handle = handle.value

    @property
    def filter(self) -> Filter | None:
        """filter(connect) -> bool decides per handler (its connect struct) whether it gets
        the calls; None: every handler.  An exception stops the call before anything is
        sent and is raised by call()."""
        return self._filter

    @filter.setter
    def filter(self, f: Filter | None) -> None:
        with self._lock:
            E.ln_event_set_filter(self.handle, self._filter_callback if f else E.EVENT_FILTER(),
                                  None)
            self._filter = f

    def _on_filter(self, connect: int | None, _user_data: int | None) -> int:
        try:
            assert self._filter is not None and connect is not None
            return 1 if self._filter(_copy(self.connect_class, connect)) else 0
        except BaseException as exc:  # noqa: BLE001 - raised by call()
            self._filter_error = exc
            return ERROR_CLASSES["LnInvalError"].code

    def call(self, fields: Any = None, /, *, timeout: float | None = None,
             **call_fields: Any) -> int:
        """Call the event with a call struct, a dict of its fields and/or keyword fields
        (missing ones 0/empty); timeout: seconds for the whole call, None waits forever.
        Returns how many handlers received it (0 if none is connected).  Raises
        LnLayoutError, LnConnectionError, ... for a failure of the call as a whole."""
        data = _struct(self.call_class, fields, call_fields,
                       f"event '{self.name}' ({self.message_definition_name} call)")
        with self._lock:
            self._filter_error = None
            try:
                delivered: int = E.ln_event_call(self.handle, ctypes.byref(data),
                                                 _timeout(timeout))
            except BaseException:
                self.results = []
                if self._filter_error is not None:
                    raise self._filter_error from None
                raise
            self.results = self._collect()
        return delivered

    def _collect(self) -> list[EventResult]:
        results = []
        for i in range(E.ln_event_result_count(self.handle)):
            r = E.EventResult()
            E.ln_event_get_result(self.handle, i, ctypes.byref(r))
            results.append(EventResult(
                (r.handler or b"").decode(), (r.client or b"").decode("utf-8", "replace"),
                r.code, (r.error or b"").decode("utf-8", "replace"),
                _copy(self.connect_class, r.connect),
                _copy(self.call_class, r.reply) if r.reply else None))
        return results

    def _release(self, handle: int) -> None:
        E.ln_event_release(handle)  # `results` stay readable


# ---- what client's methods do ----------------------------------------------------------
def connect_event(clnt: client, name: str, md_name: str, handler: Handler, connect: Any,
                  group: str | None, connect_fields: dict[str, Any]) -> event_handler:
    h = event_handler(clnt, name, md_name, handler, connect, group, connect_fields)
    clnt._providers.append(h)  # type: ignore[arg-type] - forgotten and kept alive like them
    return h


def get_event(clnt: client, name: str, md_name: str) -> event:
    ev = event(clnt, name, md_name)
    clnt._services.append(ev)  # type: ignore[arg-type] - forgotten like them on close()
    return ev


def call_event(clnt: client, name: str, md_name: str, fields: Any, timeout: float | None,
               call_fields: dict[str, Any]) -> int:
    """One call through a handle the client keeps per (name, md), with its connections."""
    cache: dict[tuple[str, str], event] = clnt.__dict__.setdefault("_event_cache", {})
    ev = cache.get((name, md_name))
    if ev is None or ev._handle is None:
        ev = cache[(name, md_name)] = get_event(clnt, name, md_name)
    return ev.call(fields, timeout=timeout, **call_fields)
