"""`ln.WaitSet`: one thread waits for whatever comes first of samples, deadlines and
publishers of subscribers, service requests, parameter overrides, file descriptors, timers
and trigger() from another thread, in one libln wait (docs/waiting.md).

    ws = ln.WaitSet()
    state = ws.attach(sub, deadline=0.1)
    tick = ws.attach_timer(0.5)
    for event in ws.wait(timeout=1.0):
        if event.kind is ln.WaitKind.DATA:
            sample = event.obj.read(timeout=0)

An attachment ends when it is detached, when the waitset is closed, or when what it watches
is closed (its close hooks, _handles.run_close_hooks, detach it before libln frees it)."""

from __future__ import annotations

import ctypes
import enum
import threading
import time
import weakref
from dataclasses import dataclass
from typing import Any

from . import _clientlib as C
from . import _waitlib as W
from . import _waits
from ._libln import ERROR_CLASSES, error_from_code

__all__ = ["Attachment", "FdEvents", "WaitEvent", "WaitKind", "WaitSet"]


class WaitKind(enum.IntEnum):
    """What fired (enum ln_waitset_kind)."""

    DATA = W.LN_WAIT_DATA              # the subscriber has a sample to read
    DEADLINE = W.LN_WAIT_DEADLINE      # no new sample for the attachment's deadline
    GONE = W.LN_WAIT_GONE              # the topic lost its last publisher
    BACK = W.LN_WAIT_BACK              # the topic has a publisher again
    REQUESTS = W.LN_WAIT_REQUESTS      # handle them: wait_and_handle_service_group_requests
    PARAMETERS = W.LN_WAIT_PARAMETERS  # overrides for the block's next update()
    FD = W.LN_WAIT_FD                  # the descriptor is ready: see WaitEvent.events
    TIMER = W.LN_WAIT_TIMER            # the timer expired `count` times
    TRIGGER = W.LN_WAIT_TRIGGER        # trigger() was called `count` times


class FdEvents(enum.IntFlag):
    """What a file descriptor is ready for (poll(2) meanings)."""

    READABLE = W.LN_WAIT_READABLE
    WRITABLE = W.LN_WAIT_WRITABLE
    ERROR = W.LN_WAIT_ERROR  # reported only: an error or hang-up


@dataclass(frozen=True, slots=True)
class WaitEvent:
    """One report of WaitSet.wait(): `kind`, the `attachment` it is about (None for
    TRIGGER) and its `obj` (the subscriber, provider, client, parameter block or the
    descriptor as attached; None for timers and TRIGGER), `count` (how often a timer,
    deadline or trigger fired since last reported, else 1) and `events` (FD only)."""

    kind: WaitKind
    attachment: Attachment | None
    obj: Any
    count: int
    events: FdEvents


class Attachment:
    """One thing attached to a WaitSet: `what` ("subscriber", "provider", "event handler",
    "service group", "parameter block", "fd", "timer"), `obj` (what was attached), `id`
    (libln's, > 0, as in WaitEvent) and `data` (given at attach, for the caller)."""

    __slots__ = ("id", "what", "obj", "data", "_waitset", "_owner", "__weakref__")

    def __init__(self, waitset: WaitSet, ident: int, what: str, obj: Any, data: Any,
                 owner: Any) -> None:
        self.id = ident
        self.what = what
        self.obj = obj
        self.data = data
        # weak: an attachment the owner keeps (through its close hooks) must not keep an
        # abandoned waitset alive, which its __del__ then closes
        self._waitset = weakref.ref(waitset)
        self._owner = owner

    @property
    def attached(self) -> bool:
        waitset = self._waitset()
        return waitset is not None and waitset._attachments.get(self.id) is self

    def detach(self) -> None:
        """End the attachment (idempotent); events of it not reported yet are dropped."""
        waitset = self._waitset()
        if waitset is not None:
            waitset._drop(self)

    def set_deadline(self, seconds: float | None) -> None:
        """A subscriber's deadline (None or 0: none), counted from now."""
        waitset = self._waitset()
        if self.what != "subscriber" or waitset is None or not self.attached:
            raise ValueError(f"{self!r} has no deadline to set")
        W.ln_waitset_set_deadline(waitset.handle, self.id, _seconds("deadline", seconds))

    def _owner_closing(self) -> None:
        self._owner = None  # its hook is gone already
        self.detach()

    def _unhook(self) -> None:
        owner, self._owner = self._owner, None
        if owner is not None:
            try:
                owner._close_hooks.remove(self._owner_closing)
            except ValueError:  # run by a close in another thread meanwhile
                pass

    def __repr__(self) -> str:
        return f"<Attachment {self.id} {self.what} {self.obj!r}>"


def _seconds(what: str, value: float | None) -> float:
    seconds = 0.0 if value is None else float(value)
    if not seconds >= 0:
        raise ValueError(f"{what} must be at least 0 seconds, not {value!r}")
    return seconds


def _fileno(fd: Any) -> int:
    number = fd if isinstance(fd, int) else fd.fileno()
    if isinstance(number, bool) or not isinstance(number, int) or number < 0:
        raise ValueError(f"not a file descriptor: {fd!r}")
    return number


_wait = W.ln_waitset_wait
_monotonic = time.monotonic


class WaitSet:
    """A libln waitset.  Attach what to wait for, then wait() in one thread at a time;
    attach, detach and trigger() work from any thread, also while another one waits.
    `capacity`: how many events one wait() reports at most (the others stay pending for
    the next).  close() (or the end of a `with` block) detaches everything; closing a
    waitset in which another thread waits wakes that thread, whose wait() then raises
    ValueError."""

    def __init__(self, capacity: int = 64) -> None:
        if not 1 <= capacity <= W.LN_WAITSET_MAX_ATTACHMENTS:
            raise ValueError(f"capacity must be 1 .. {W.LN_WAITSET_MAX_ATTACHMENTS}")
        handle = ctypes.c_void_p()
        W.ln_waitset_create(ctypes.byref(handle))
        self._handle: int | None = handle.value
        self.capacity = capacity
        self._events = (W.WaitsetEvent * capacity)()
        self._attachments: dict[int, Attachment] = {}
        self._lock = threading.Lock()  # _handle, _attachments, _waiter
        self._idle = threading.Condition(self._lock)
        self._waiter: int | None = None  # the thread in wait()
        self._closing = False

    @property
    def handle(self) -> int:
        if self._handle is None or self._closing:
            raise ValueError("waitset is closed")
        return self._handle

    @property
    def attachments(self) -> list[Attachment]:
        with self._lock:
            return list(self._attachments.values())

    # ---- attaching ----
    def attach(self, obj: Any, **options: Any) -> Attachment:
        """Attach `obj` by its type: a subscriber (options of attach_subscriber), a service
        provider or event handler, a client (its default service group, or group=...), a
        parameter block, or a file descriptor (an int or anything with fileno())."""
        from ._client import client, subscriber
        from ._events import event_handler
        from ._services import provided_service

        if isinstance(obj, subscriber):
            return self.attach_subscriber(obj, **options)
        if isinstance(obj, (provided_service, event_handler)):
            return self.attach_provider(obj, **options)
        if isinstance(obj, client):
            return self.attach_service_group(obj, **options)
        if isinstance(obj, int) or hasattr(obj, "fileno"):
            return self.attach_fd(obj, **options)
        from ._parameters import parameter_block  # numpy: only when needed

        if isinstance(obj, parameter_block):
            return self.attach_parameter_block(obj, **options)
        raise TypeError(f"cannot wait on {type(obj).__name__} (a subscriber, provider, event "
                        "handler, client, parameter block or file descriptor)")

    def attach_subscriber(self, sub: Any, *, data: bool = True, liveliness: bool = False,
                          deadline: float | None = None, user: Any = None) -> Attachment:
        """Report DATA while `sub` has samples to read (`data`), GONE/BACK when its topic
        loses its last publisher or gets one again (`liveliness`), DEADLINE each time
        `deadline` seconds pass without a new sample.  `user` becomes Attachment.data."""
        if not (data or liveliness):
            raise ValueError("attach a subscriber for data, liveliness or both")
        flags = (W.LN_WAIT_ON_DATA if data else 0) | (W.LN_WAIT_ON_LIVELINESS if liveliness
                                                       else 0)
        seconds = _seconds("deadline", deadline)
        return self._attach("subscriber", sub, sub, user, lambda ws, out: W.ln_waitset_attach_inport(
            ws, sub.handle, flags, seconds, None, out))

    def attach_provider(self, provider: Any, *, user: Any = None) -> Attachment:
        """Report REQUESTS when the service group of `provider` (a provided_service or an
        event_handler) has requests: handle them with
        `client.wait_and_handle_service_group_requests(provider.group, 0)`."""
        from ._events import event_handler

        if isinstance(provider, event_handler):
            return self._attach("event handler", provider, provider, user,
                                lambda ws, out: W.ln_waitset_attach_event_handler(
                                    ws, provider.handle, None, out))
        return self._attach("provider", provider, provider, user,
                            lambda ws, out: W.ln_waitset_attach_provider(
                                ws, provider.handle, None, out))

    def attach_service_group(self, clnt: Any, group: str | None = None, *,
                             user: Any = None) -> Attachment:
        """Report REQUESTS when service group `group` of `clnt` (None: the default group)
        has requests (a provider must be registered in it)."""
        name = None if group is None else group.encode()
        return self._attach("service group", clnt, clnt, user,
                            lambda ws, out: W.ln_waitset_attach_service_group(
                                ws, clnt.handle, name, None, out))

    def attach_parameter_block(self, block: Any, *, user: Any = None) -> Attachment:
        """Report PARAMETERS when overrides arrived for `block`: take them with update()."""
        return self._attach("parameter block", block, block, user,
                            lambda ws, out: W.ln_waitset_attach_parameter_block(
                                ws, block.handle, None, out))

    def attach_fd(self, fd: Any, *, readable: bool = True, writable: bool = False,
                  user: Any = None) -> Attachment:
        """Report FD while `fd` (an int or an object with fileno(), kept open by the caller
        while attached) is readable and/or writable (level-triggered)."""
        number = _fileno(fd)
        events = (W.LN_WAIT_READABLE if readable else 0) | (W.LN_WAIT_WRITABLE if writable
                                                             else 0)
        if not events:
            raise ValueError("attach a file descriptor for reading, writing or both")
        return self._attach("fd", fd, None, user, lambda ws, out: W.ln_waitset_attach_fd(
            ws, number, events, None, out))

    def attach_timer(self, period: float, *, delay: float | None = None,
                     user: Any = None) -> Attachment:
        """Report TIMER first after `delay` seconds (None: one period), then every `period`
        seconds after the previous expiry (0: once only), on absolute times: it does not
        drift, and when the waiter falls behind it skips expiries (WaitEvent.count)."""
        period = _seconds("period", period)
        if delay is None:
            if period == 0:
                raise ValueError("a timer that fires once needs a delay")
            first_ns = 0
        else:
            first_ns = time.monotonic_ns() + max(1, round(_seconds("delay", delay) * 1e9))
        return self._attach("timer", None, None, user, lambda ws, out: W.ln_waitset_attach_timer(
            ws, first_ns, period, None, out))

    def _attach(self, what: str, obj: Any, owner: Any, user: Any, call: Any) -> Attachment:
        """`call(waitset handle, id out)` attaches in libln; `owner` (None for descriptors
        and timers) gets a close hook that detaches before it is freed."""
        ident = ctypes.c_uint32()
        with self._lock:
            call(self.handle, ctypes.byref(ident))
            attachment = Attachment(self, ident.value, what, obj, user, owner)
            self._attachments[attachment.id] = attachment
        if owner is not None:
            owner._close_hooks.append(attachment._owner_closing)
        return attachment

    def detach(self, attachment: Attachment) -> None:
        """attachment.detach()."""
        attachment.detach()

    def _drop(self, attachment: Attachment) -> None:
        with self._lock:
            if self._attachments.get(attachment.id) is not attachment:
                return
            del self._attachments[attachment.id]
            if self._handle is not None:
                W.ln_waitset_detach(self._handle, attachment.id)
        attachment._unhook()

    # ---- waiting ----
    def wait(self, timeout: float | None = None) -> list[WaitEvent]:
        """Wait up to `timeout` seconds (None: forever, 0: only what is ready now) for
        something to fire; returns what did (empty: the timeout passed).  The GIL is
        released meanwhile; a signal runs Python's handlers (Ctrl-C raises
        KeyboardInterrupt) and the wait goes on for the rest of the time."""
        t = -1.0 if timeout is None else float(timeout)
        start = _monotonic() if t > 0 else 0.0
        with self._lock:
            handle = self.handle
            if self._waiter is not None:
                raise ERROR_CLASSES["LnBusyError"]("another thread waits in this waitset")
            self._waiter = threading.get_ident()
        try:
            n = _wait(handle, t, self._events, self.capacity)
            if n == C.LN_EINTR:
                n = self._wait_on(handle, _waits.end_of(timeout, start))
            if self._closing:
                raise ValueError("waitset is closed")
            if n < 0:
                raise error_from_code(n, C.last_error())
            return self._reports(n)
        finally:
            with self._lock:
                self._waiter = None
                self._idle.notify_all()

    def _wait_on(self, handle: int, end: float) -> int:
        """Waits after a signal interrupted one, until one ends otherwise."""
        while True:
            _waits.run_signal_handlers()
            if self._closing:
                raise ValueError("waitset is closed")
            n = _wait(handle, _waits.remaining(end), self._events, self.capacity)
            if n != C.LN_EINTR:
                return n

    def _reports(self, n: int) -> list[WaitEvent]:
        reports = []
        attachments = self._attachments
        for i in range(n):
            event = self._events[i]
            kind = WaitKind(event.kind)
            attachment = None
            if kind is not WaitKind.TRIGGER:
                attachment = attachments.get(event.id)
                if attachment is None:  # detached by another thread meanwhile
                    continue
            reports.append(WaitEvent(kind, attachment, None if attachment is None
                                     else attachment.obj, event.count, FdEvents(event.events)))
        return reports

    def trigger(self) -> None:
        """Wake the wait (from any thread, or a signal handler): it reports TRIGGER."""
        W.ln_waitset_trigger(self.handle)

    def fileno(self) -> int:
        """A descriptor that becomes readable when a wait may report something (for
        another event loop: then wait(0)); it belongs to the waitset."""
        return int(W.ln_waitset_fd(self.handle))

    def next_due(self) -> int | None:
        """When the next timer or deadline falls due (time.monotonic_ns()), None if none."""
        ns = ctypes.c_int64()
        W.ln_waitset_next_due(self.handle, ctypes.byref(ns))
        return None if ns.value < 0 else ns.value

    # ---- closing ----
    def close(self) -> None:
        """Detach everything and free the waitset (idempotent); a wait() in another thread
        wakes and raises ValueError."""
        with self._lock:
            if self._handle is None:
                return
            if self._waiter == threading.get_ident():
                raise ERROR_CLASSES["LnBusyError"]("a waitset cannot be closed inside its wait")
            self._closing = True
            if self._waiter is not None:
                W.ln_waitset_trigger(self._handle)
            self._idle.wait_for(lambda: self._waiter is None)
            handle, self._handle = self._handle, None
            attachments = list(self._attachments.values())
            self._attachments.clear()
        for attachment in attachments:
            attachment._unhook()
        W.ln_waitset_destroy(handle)

    @property
    def closed(self) -> bool:
        return self._handle is None

    def __enter__(self) -> WaitSet:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # noqa: BLE001 - interpreter shutdown
            pass
