"""The Python service API: callers (`service`), providers (`provided_service`, whose handler
gets a `service_request`) and `service_provider`, the LN base class that turns methods into
services.

    svc = clnt.get_service("robot.set_gains", "robot/set_gains")
    svc.req.kp = kp
    svc.req.profile_name = "soft"
    svc.call(timeout=1.0)
    print(svc.resp.ok, svc.resp.message)

libln encodes, sends, decodes and checks everything; this module holds handles, message
structs and the ctypes callback, and copies decoded data out of libln's memory so that no
Python object ever points into memory libln may free.
"""

from __future__ import annotations

import ctypes
import logging
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from . import _clientlib as C
from . import _waits as W
from ._handles import CallerHandle, HandlerHandle, handling, keep_for_wait, thread_state
from ._libln import ERROR_CLASSES, error_from_code
from .md_loader import message_class
from .md_types import LnStruct, own_dynamic_data

if TYPE_CHECKING:
    from ._client import client

__all__ = ["provided_service", "service", "service_provider", "service_request"]

_log = logging.getLogger("links_and_nodes.services")


def _timeout(timeout: float | None) -> float:
    return -1.0 if timeout is None else float(timeout)


def _name_arg(name: str | None) -> bytes | None:
    return None if name is None else name.encode()


def _sections(md_name: str) -> tuple[type[LnStruct], type[LnStruct], type[LnStruct]]:
    """The service class of `md_name` and its request and response classes."""
    cls = message_class(md_name)
    if getattr(cls, "KIND", None) != "service":
        raise ERROR_CLASSES["LnMdError"](
            f"'{md_name}' is not a service definition (it has no request/response sections)")
    parts = {name: elem for name, _kind, elem, _count in cls._ln_specs_}
    return cls, parts["req"], parts["resp"]


def _clear(obj: LnStruct) -> None:
    """Zero a struct and drop the buffers it kept alive (no pointer survives)."""
    ctypes.memset(ctypes.addressof(obj), 0, ctypes.sizeof(obj))
    obj.__dict__.pop("_ln_keep", None)


def error_text(exc: BaseException) -> str:
    """The error response for an exception of a handler: "TypeName: message"."""
    message = str(exc)
    return f"{type(exc).__name__}: {message}" if message else type(exc).__name__


# ---- callers -------------------------------------------------------------------------------
class service(CallerHandle):  # noqa: N801 - the LN name
    """A caller's handle of service `name`; made by `client.get_service`.

    `req` and `resp` are structs of the md's request and response sections.  `call()` sends
    `req` and fills `resp`; the dynamic fields of `resp` are copied out of libln, so `resp`
    and every value read from it stay valid after later calls and after `close()`.
    A failed call raises and leaves `resp` as it was.  Calls on one handle are serialized;
    use one handle per thread for parallel calls."""

    _what = "service"

    def __init__(self, clnt: client, name: str, md_name: str) -> None:
        super().__init__(clnt, name, md_name)
        self.service_class, self.request_class, self.response_class = _sections(md_name)
        self.req: Any = self.request_class()
        self.resp: Any = self.response_class()
        self._raw = self.response_class()  # filled by libln, points into its memory
        handle = ctypes.c_void_p()
        C.ln_get_service(clnt.handle, ctypes.byref(handle), name.encode(), md_name.encode(),
                         self.service_class.LAYOUT_HASH, self.service_class.SIGNATURE.encode())
        self._handle = handle.value

    def call(self, timeout: float | None = None) -> Any:
        """Send `req`, wait for the response and return `resp` (filled with it).

        timeout: seconds, None waits forever.  Raises LnServiceError with the provider's
        text for an error response, LnTimeoutError, LnNotfoundError, LnLayoutError,
        LnConnectionError, ... (see docs/services.md)."""
        with self._lock:
            return self._call_locked(self.req, self.resp, timeout)

    async def call_async(self, req: LnStruct | dict[str, Any] | None = None,
                         timeout: float | None = None) -> Any:
        """`await svc.call_async(req, timeout)`: call() without blocking the event loop.
        `req` (a request struct or a dict of its fields; None: `self.req`) is sent as it is
        when the call starts.  Returns a response struct of its own (`resp` stays as it
        was), so calls of several tasks on one handle (serialized) never mix.  The call
        runs in the loop's default executor (libln's calls block); a cancelled caller stops
        waiting at once while the call ends in its thread (by `timeout` at the latest)."""
        from ._async_waits import call_async

        return await call_async(self, req, timeout)

    def _call_with(self, req: LnStruct | dict[str, Any] | None, timeout: float | None) -> Any:
        """call() with request `req` into a new response (call_async's, in an executor
        thread)."""
        resp = self.response_class()
        with self._lock:
            if req is None:
                return self._call_locked(self.req, resp, timeout)
            if isinstance(req, dict):
                struct = self.request_class()
                struct.update(req)
                req = struct
            elif not isinstance(req, self.request_class):
                raise TypeError(f"{self.message_definition_name}: a request struct of this md "
                                f"or a dict, not {type(req).__name__}")
            return self._call_locked(req, resp, timeout)

    def _call_locked(self, req: LnStruct, resp: LnStruct, timeout: float | None) -> Any:
        """One call (under _lock): sends `req`, copies the response into `resp`."""
        C.ln_service_call(self.handle, ctypes.byref(req), ctypes.byref(self._raw),
                          _timeout(timeout))
        try:
            ctypes.memmove(ctypes.addressof(resp), ctypes.addressof(self._raw),
                           ctypes.sizeof(self._raw))
            own_dynamic_data(resp)
        except BaseException:
            _clear(resp)
            raise
        finally:
            _clear(self._raw)
        return resp

    def set_max_size(self, max_bytes: int) -> None:
        """Largest response accepted (wire bytes plus decoded dynamic data)."""
        C.ln_service_set_max_size(self.handle, max_bytes)

    def _release(self, handle: int) -> None:
        C.ln_service_release(handle)  # `resp` stays readable


# ---- providers -----------------------------------------------------------------------------
class service_request:  # noqa: N801
    """One call of a provided service, as its handler sees it; valid only during the handler.

    `req` holds the decoded request (its own copy: it may be kept after the handler),
    `resp` is an empty response struct to fill before `respond()`."""

    def __init__(self, provider: provided_service, handle: int) -> None:
        self.provider = provider
        self.req: Any = provider.request_class()
        self.resp: Any = provider.response_class()
        self.responded = False
        self._handle: int | None = handle

    @property
    def service_name(self) -> str:
        return self.provider.name

    def _live(self) -> int:
        if self._handle is None:
            raise ValueError(f"request of service '{self.provider.name}' is over: answer it "
                             "inside its handler")
        return self._handle

    def _read(self) -> None:
        C.ln_service_request_get_data(self._live(), ctypes.byref(self.req))
        try:
            own_dynamic_data(self.req)
        except BaseException:
            _clear(self.req)
            raise

    def respond(self, resp: LnStruct | dict[str, Any] | None = None) -> None:
        """Answer with `resp` (default: self.resp): a response struct of this md, or a dict
        of its fields (set in self.resp).  The response is encoded at once."""
        handle = self._live()
        if resp is None:
            resp = self.resp
        elif isinstance(resp, dict):
            self.resp.update(resp)
            resp = self.resp
        elif not isinstance(resp, self.provider.response_class):
            raise TypeError(f"{self.provider.message_definition_name}: respond() takes a "
                            f"response struct of this md or a dict, not {type(resp).__name__}")
        C.ln_service_request_respond(handle, ctypes.byref(resp))
        self.responded = True

    def respond_error(self, text: str) -> None:
        """Answer with an error: the caller's call raises LnServiceError with `text`."""
        C.ln_service_request_respond_error(self._live(), text.encode("utf-8", "replace"))
        self.responded = True


Handler = Callable[[service_request], None]


class provided_service(HandlerHandle):  # noqa: N801
    """A service this client provides; made (and registered) by `client.get_service_provider`.

    `handler(request)` runs once per call, in the thread that handles the group (see
    `client.wait_and_handle_service_group_requests` and thread pools), and answers with
    `request.respond()` or `request.respond_error(text)`.  An exception it raises is
    answered as an error "TypeName: message"; a handler that returns without answering
    makes libln answer "handler returned without responding"."""

    def __init__(self, clnt: client, name: str, md_name: str, handler: Handler,
                 group: str | None = None, max_size: int | None = None) -> None:
        super().__init__(clnt, name, md_name, group)
        self.handler = handler
        self.service_class, self.request_class, self.response_class = _sections(md_name)
        # libln calls this from whichever thread handles the group; it must live as long as
        # libln may call it: until unregistered, or the client is destroyed.
        self._callback = C.SERVICE_HANDLER(self._on_request)
        handle = ctypes.c_void_p()
        C.ln_get_service_provider(clnt.handle, ctypes.byref(handle), name.encode(),
                                  md_name.encode(), self.service_class.LAYOUT_HASH,
                                  self.service_class.SIGNATURE.encode())
        self._handle = handle.value
        try:
            C.ln_service_provider_set_handler(self._handle, self._callback, None)
            if max_size is not None:
                C.ln_service_provider_set_max_size(self._handle, max_size)
            C.ln_service_provider_register(self._handle, _name_arg(group))
        except BaseException:
            handle_value, self._handle = self._handle, None
            C.ln_unregister_service_provider(handle_value)
            raise

    def _on_request(self, _clnt: int | None, req: int | None, _user_data: int | None) -> int:
        # Runs under the GIL, called by libln; must never raise into ctypes.
        try:
            request = service_request(self, req or 0)
        except BaseException as exc:  # noqa: BLE001 - e.g. MemoryError
            _answer_failure(None, req, self.name, exc)
            return 0
        with handling(self.client):
            try:  # the request's handle is valid only until this returns
                request._read()
                self.handler(request)
            except BaseException as exc:  # noqa: BLE001 - becomes the error response
                _answer_failure(request, req, self.name, exc)
            finally:
                request._handle = None
        return 0

    _what = "provider of service"

    def _release(self, handle: int) -> None:
        C.ln_unregister_service_provider(handle)


def _answer_failure(request: service_request | None, req: int | None, name: str,
                    exc: BaseException) -> None:
    """Answer a call whose handler raised `exc` with an error (if it was not answered yet)."""
    text = error_text(exc)
    _log.info("service '%s': handler failed: %s", name, text, exc_info=exc)
    if request is not None and request.responded:
        pass  # answered already; the exception only reaches the log
    elif req:
        try:
            C.ln_service_request_respond_error(req, text.encode("utf-8", "replace"))
        except Exception:  # noqa: BLE001 - nothing left to tell the caller
            _log.info("service '%s': could not answer with an error", name, exc_info=True)
    keep_for_wait(exc, f"service '{name}'")


def wait_and_handle(clnt: client, group: str | None, timeout: float | None) -> int:
    """client.wait_and_handle_service_group_requests (handlers run in this thread).

    A long wait is made of slices (see _waits), so that client.close() from another
    thread need not wait longer than one of them."""
    name = _name_arg(group)
    handle = clnt._enter_wait()
    previous = getattr(thread_state, "waiting", False)
    thread_state.waiting = True
    thread_state.pending = None
    try:
        rc = C.ln_wait_and_handle_service_group_requests(handle, name, W.first_slice(timeout))
        if rc == 0 and W.waits_longer(timeout):
            end = W.deadline(timeout)
            while rc == 0 and (t := W.next_slice(end)) > 0:
                if clnt._closing:
                    raise ValueError("client is closed")
                rc = C.ln_wait_and_handle_service_group_requests(handle, name, t)
    finally:
        thread_state.waiting = previous
        pending, thread_state.pending = thread_state.pending, None
        clnt._leave_wait()
    if pending is not None:
        raise pending
    if rc == C.LN_EINTR:
        return 0  # a signal: Python runs its handler (KeyboardInterrupt) next
    if rc < 0:
        raise error_from_code(rc, C.last_error())
    return rc


def in_handler_of(clnt: client) -> bool:
    """Whether this thread runs a service handler of `clnt` (libln is below it)."""
    return clnt in getattr(thread_state, "handling", ())


# ---- the LN wrapper ------------------------------------------------------------------------
def _method_name(name: str) -> str:
    return "".join(c if c.isalnum() or c == "_" else "_" for c in name)


class service_provider:  # noqa: N801 - the LN name
    """Base class that provides services through its methods:

        class gains(ln.service_provider):
            def __init__(self, clnt):
                ln.service_provider.__init__(self, clnt, "robot")
                self.wrap_service_provider("set_gains", "robot/set_gains")

            def set_gains(self, kp, kd, profile_name):
                return {"ok": 1, "message": ""}

    provides service "robot.set_gains"; see `wrap_service_provider` for the conventions."""

    def __init__(self, clnt: client, service_name_prefix: str = "") -> None:
        self.client = clnt
        self.service_name_prefix = service_name_prefix
        self.provided_services: dict[str, provided_service] = {}

    def wrap_service_provider(self, name: str, md_name: str, group: str | None = None,
                              method: Callable[..., Any] | None = None,
                              max_size: int | None = None) -> provided_service:
        """Provide service "PREFIX.name" (just `name` without a prefix) of md `md_name`.

        Each call runs `method` (default: the method called `name`, with characters other
        than letters, digits and "_" replaced by "_") with the request fields as keyword
        arguments: numbers as int/float, char fields as str, numeric arrays as numpy
        arrays, nested structs as structs and arrays of them as ctypes arrays of structs
        (all owned by the request: they may be kept).  It returns the response: a dict of
        its fields (missing ones stay 0/empty), a response struct, the bare value of the
        only field when the response has exactly one, or None when it has none.  An
        exception becomes an error response "TypeName: message"."""
        full_name = f"{self.service_name_prefix}.{name}" if self.service_name_prefix else name
        if method is None:
            method = getattr(self, _method_name(name))
        provider = self.client.get_service_provider(
            full_name, md_name, _method_handler(method, full_name), group, max_size)
        self.provided_services[full_name] = provider
        return provider

    def close(self) -> None:
        """Unregister every service of this provider."""
        for provider in list(self.provided_services.values()):
            provider.close()
        self.provided_services.clear()


def _method_handler(method: Callable[..., Any], full_name: str) -> Handler:
    def handler(request: service_request) -> None:
        provider = request.provider
        fields = {name: getattr(request.req, name)
                  for name, *_ in provider.request_class._ln_specs_}
        result = method(**fields)
        request.respond(_response(provider, full_name, result))

    return handler


def _response(provider: provided_service, full_name: str, result: Any) -> Any:
    """What a wrapped method returned, as a response struct or dict for respond()."""
    cls = provider.response_class
    names = [name for name, *_ in cls._ln_specs_]
    if isinstance(result, (dict, cls)):
        return result
    if result is None:
        if names:
            raise TypeError(f"{full_name}: returned None, but the response of "
                            f"{provider.message_definition_name} has fields {', '.join(names)}")
        return None
    if len(names) != 1:
        raise TypeError(f"{full_name}: returned {type(result).__name__}; the response of "
                        f"{provider.message_definition_name} has fields "
                        f"{', '.join(names) or '(none)'}: return a dict of them")
    return {names[0]: result}
