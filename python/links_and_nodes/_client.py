"""The Python client API: `ln.client`, publishers and subscribers (LN names and habits);
services are in _services.py.

    clnt = ln.client("planner")
    pub = clnt.publish("robot.state", "robot/joint_state")
    pub.packet.position[:] = q
    pub.write()
    sub = clnt.subscribe("robot.state", "robot/joint_state", buffers=16)
    pkt = sub.read(timeout=1.0)   # None if nothing came within the timeout

Everything runs through libln; these classes only hold handles and message objects.
"""

from __future__ import annotations

import atexit
import ctypes
import json
import operator
import threading
import time
import weakref
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any, NoReturn

from . import _clientlib as C
from . import _services, transports
from . import _waits as W
from ._handles import run_close_hooks
from ._libln import ERROR_CLASSES, ERRORS_BY_CODE, error_from_code
from ._services import Handler, provided_service, service
from .md_loader import message_class
from .md_types import LnStruct


def _timeout(timeout: float | None) -> float:
    return -1.0 if timeout is None else float(timeout)


class client:  # noqa: N801 - the LN name
    """A connection to the manager.  `ln_manager_or_args` is "HOST:PORT", an argv list
    (searched for `-ln_manager HOST:PORT`), or None for $LN_MANAGER.  With `reconnect` (the
    default, unless LN_RECONNECT=0) libln reconnects to a restarted manager and registers
    the client's ports and services again (docs/manager.md)."""

    def __init__(self, name: str, ln_manager_or_args: str | Sequence[str] | None = None,
                 timeout: float = 10.0, reconnect: bool = True) -> None:
        opts = C.ClientOptions()
        C.ln_client_options_init(ctypes.byref(opts))
        opts.timeout = timeout
        if not reconnect:
            opts.flags |= C.LN_CLIENT_NO_RECONNECT
        self._argv_keep: Any = None
        if isinstance(ln_manager_or_args, str):
            opts.manager = ln_manager_or_args.encode()
        elif ln_manager_or_args is not None:
            args = [a.encode() for a in ln_manager_or_args]
            self._argv_keep = (ctypes.c_char_p * (len(args) + 1))(*args, None)
            opts.argc = len(args)
            opts.argv = self._argv_keep
        handle = ctypes.c_void_p()
        C.ln_client_create(ctypes.byref(handle), name.encode(), ctypes.byref(opts))
        self._handle: int | None = handle.value
        self._ports: list[_Port] = []
        self._services: list[service] = []
        self._providers: list[provided_service] = []
        # Threads inside wait_and_handle_service_group_requests (ident -> depth): close()
        # waits for them, so libln never frees the client under a running wait.
        self._waiting: dict[int, int] = {}
        self._waiting_changed = threading.Condition()
        self._closing = False
        self._close_hooks: list[Callable[[], None]] = []  # its waitset attachments (_handles)
        self.name: str = C.ln_client_name(self._handle).decode()

    @property
    def handle(self) -> int:
        if self._handle is None:
            raise ValueError("client is closed")
        return self._handle

    def publish(self, topic_name: str, message_definition_name: str, buffers: int = 1,
                wait_for_subscribers: bool = False) -> publisher:
        port = publisher(self, topic_name, message_definition_name, buffers,
                         wait_for_subscribers)
        self._ports.append(port)
        return port

    def subscribe(self, topic_name: str, message_definition_name: str,
                  buffers: int = 1, spin_us: int | None = None,
                  transport: str | None = None) -> subscriber:
        """buffers=1: *latest* mode; buffers=N > 1: *queued* mode with N buffers.  spin_us:
        how long a blocking read polls before it sleeps (default: libln's, 20 us).
        transport: "udp" or "tcp", how samples of a publisher on another host reach this
        one (docs/network.md); None leaves it to the topic's setting."""
        port = subscriber(self, topic_name, message_definition_name, buffers, spin_us,
                          transport)
        self._ports.append(port)
        return port

    def use_clock(self, topic: str | None = None) -> None:
        """Make now() follow the replay clock of an `ln_play --clock` on `topic` (None:
        "ln.clock"; docs/recording.md, "Replay control and the replay clock")."""
        C.ln_client_use_clock(self.handle, None if topic is None else topic.encode())

    def now(self) -> int:
        """ns since the epoch: CLOCK_REALTIME, or after use_clock() the replay time (0 before
        the first clock sample; it stands still while the replay is paused).  Never blocks."""
        ns = ctypes.c_int64()
        C.ln_now(self.handle, ctypes.byref(ns))
        return ns.value

    @property
    def last_error(self) -> tuple[int, str]:
        """(code, text) of the last error on this client or its ports, from any thread."""
        buf = ctypes.create_string_buffer(2048)
        code = C.ln_client_last_error(self.handle, buf, len(buf))
        return code, buf.value.decode("utf-8", "replace")

    def control(self, op: str, **args: Any) -> dict[str, Any]:
        """One manager control command on this client's connection (docs/protocol.md,
        "Control"): its JSON answer as a dict; a refusal raises the LnError class of the
        code it names (LnRefusedError by default) with the manager's reason."""
        result = ctypes.c_void_p()
        C.ln_control(self.handle, json.dumps({"op": op, **args}).encode(),
                     ctypes.byref(result))
        try:
            text = ctypes.string_at(result.value).decode() if result.value else "{}"
        finally:
            C.ln_free(result)
        answer: dict[str, Any] = json.loads(text)
        return answer

    def get_logger(self, name: str) -> Any:
        """The manager's topic logger `name` (made if it does not exist; docs/logging.md)."""
        from ._logger import logger

        return logger(self, name)

    def unpublish(self, port: publisher) -> None:
        port.close()

    def unsubscribe(self, port: subscriber) -> None:
        port.close()

    # ---- services (see _services.py and docs/services.md) ----
    def get_service(self, name: str, message_definition_name: str) -> service:
        """A caller's handle of service `name` with md `message_definition_name`: fill
        `svc.req`, `svc.call(timeout)`, read `svc.resp`.  Nothing is contacted before the
        first call."""
        svc = service(self, name, message_definition_name)
        self._services.append(svc)
        return svc

    def release_service(self, svc: service) -> None:
        svc.close()

    def get_service_provider(self, name: str, message_definition_name: str,
                             handler: Handler, group: str | None = None,
                             max_size: int | None = None) -> provided_service:
        """Provide service `name`: registers it in `group` (None: the default group) at once.
        `handler(request)` answers each call with request.respond() or
        request.respond_error(text); max_size: largest request accepted (bytes)."""
        provider = provided_service(self, name, message_definition_name, handler, group,
                                    max_size)
        self._providers.append(provider)
        return provider

    def unregister_service_provider(self, provider: provided_service) -> None:
        provider.close()

    # ---- asyncio (see _async_waits.py, _async_provider.py and docs/waiting.md) ----
    def provide_async(self, name: str, message_definition_name: str, handler: Any,
                      group: str | None = None, max_size: int | None = None,
                      loop: Any = None) -> provided_service:
        """Provide service `name` with `handler(request)`, a coroutine function, run on
        `loop` (default: the running one): it answers with request.respond() or returns the
        response (a struct or a dict).  The provider's service group (default: one of its
        own, "asyncio.NAME") is served through the loop's waitset; close() it before the
        loop ends."""
        import asyncio

        from ._async_provider import async_provided_service

        provider = async_provided_service(self, name, message_definition_name, handler, group,
                                          max_size, loop or asyncio.get_running_loop())
        self._providers.append(provider)
        return provider

    async def wait_publisher(self, topic: str | subscriber, md_name: str | None = None,
                             timeout: float | None = None) -> bool:
        """`await clnt.wait_publisher(topic)`: until the topic (a subscriber, or the name of
        a topic this client subscribes, else pass its `md_name`) has a publisher; True, or
        False after `timeout` seconds (None: no limit)."""
        from ._async_waits import wait_topic_publisher

        return await wait_topic_publisher(self, topic, md_name, timeout)

    # ---- events (see _events.py and docs/events.md) ----
    def connect_event(self, name: str, message_definition_name: str,
                      handler: Callable[[Any], Any], connect: Any = None, *,
                      group: str | None = None, **connect_fields: Any) -> Any:
        """Connect `handler(call)` to event `name` with the connect struct `connect` (a
        struct or dict) and/or keyword fields; its calls are handled with the service
        group `group`.  Returns the event_handler (close() disconnects it)."""
        from . import _events

        return _events.connect_event(self, name, message_definition_name, handler, connect,
                                     group, connect_fields)

    def get_event(self, name: str, message_definition_name: str) -> Any:
        """A caller's handle of event `name`: ev.call(**fields), ev.results, ev.filter."""
        from . import _events

        return _events.get_event(self, name, message_definition_name)

    def call_event(self, name: str, message_definition_name: str, fields: Any = None, *,
                   timeout: float | None = None, **call_fields: Any) -> int:
        """Call event `name` once (through a handle the client keeps): returns how many
        handlers received the call."""
        from . import _events

        return _events.call_event(self, name, message_definition_name, fields, timeout,
                                  call_fields)

    # ---- parameters (see _parameters.py and docs/parameters.md) ----
    def get_parameter_block(self, name: str) -> Any:
        """A new parameter block `name` of this client: add(), register(), update()."""
        from ._parameters import parameter_block

        return parameter_block(self, name)

    def wait_and_handle_service_group_requests(self, group: str | None = None,
                                               timeout: float | None = None) -> int:
        """Wait up to `timeout` seconds (None: forever) for a request of `group`, then
        handle every request that is ready, in this thread; returns how many were handled."""
        return _services.wait_and_handle(self, group, timeout)

    def handle_service_group_in_thread_pool(self, group: str | None, pool: str) -> None:
        """From now on the threads of `pool` handle the requests of `group` (concurrently up
        to the pool's set_max_threads, default 1); handlers then run in those threads."""
        C.ln_handle_service_group_in_thread_pool(self.handle, _services._name_arg(group),
                                                 pool.encode())
        _pool_clients.add(self)

    def set_max_threads(self, pool: str, max_threads: int) -> None:
        """Maximum number of threads of thread pool `pool` (1 .. 256)."""
        C.ln_set_max_threads(self.handle, pool.encode(), max_threads)

    def _enter_wait(self) -> int:
        """The handle, for a wait_and_handle_service_group_requests that starts now."""
        with self._waiting_changed:
            if self._closing:
                raise ValueError("client is closed")
            handle = self.handle
            me = threading.get_ident()
            self._waiting[me] = self._waiting.get(me, 0) + 1
            return handle

    def _leave_wait(self) -> None:
        with self._waiting_changed:
            me = threading.get_ident()
            self._waiting[me] -= 1
            if not self._waiting[me]:
                del self._waiting[me]
            self._waiting_changed.notify_all()

    def close(self) -> None:
        """Close every port, service and provider and the connection (idempotent).

        Calls running in other threads end first: a blocking read at once, a write or
        wait_and_handle_service_group_requests within 0.1 s (then raising ValueError), a
        service call when it returns.  From inside a service handler of this client it
        raises LnBusyError."""
        if _services.in_handler_of(self):
            raise ERROR_CLASSES["LnBusyError"](
                f"client '{self.name}' cannot be closed inside one of its service handlers")
        # first end the waitset attachments of everything, which also stops the handlers of
        # asyncio providers from waiting for their coroutines (the waits below would not end)
        for owner in (*self._ports, *self._providers, self):
            run_close_hooks(owner)
        with self._waiting_changed:
            self._closing = True  # no new wait starts, running ones end after their slice
            me = threading.get_ident()
            self._waiting_changed.wait_for(lambda: all(t == me for t in self._waiting))
        for port in reversed(self._ports):
            port._forget()  # libln closes them with the client
        self._ports.clear()
        for svc in self._services:
            svc._forget()
        self._services.clear()
        providers, self._providers = self._providers, []
        for provider in providers:
            provider._forget()
        if self._handle is not None:
            handle, self._handle = self._handle, None
            C.ln_client_destroy(handle)  # stops thread pools, frees providers
        del providers  # their ctypes callbacks may go only now

    def __enter__(self) -> client:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # noqa: BLE001 - interpreter shutdown
            pass


# Clients whose thread pools may call into Python: closed before the interpreter shuts down.
_pool_clients: weakref.WeakSet[client] = weakref.WeakSet()


@atexit.register
def _close_pool_clients() -> None:
    for clnt in list(_pool_clients):
        clnt.close()


_ln_read = C.ln_read
_ln_read_borrow = C.ln_read_borrow
_ln_read_release = C.ln_read_release
_ln_write = C.ln_write
_ln_write_loan = C.ln_write_loan
_ln_write_commit = C.ln_write_commit
_ln_write_abort = C.ln_write_abort
_TimeoutError = ERRORS_BY_CODE[C.LN_ETIMEOUT]
_monotonic = time.monotonic
# subscribe(transport=...): the LN_SUBSCRIBE_* flag of each name
_TRANSPORTS = {transports.UDP: C.LN_SUBSCRIBE_UDP, transports.TCP: C.LN_SUBSCRIBE_TCP}
def _uint32(what: str, value: Any, low: int) -> int:
    """`value` as a whole number from `low` to 2**32 - 1, else TypeError / ValueError."""
    if isinstance(value, bool):
        raise TypeError(f"{what} must be an integer, not bool")
    number = operator.index(value)  # TypeError for 2.5, "4", None
    if not low <= number <= 0xFFFFFFFF:
        raise ValueError(f"{what} must be at least {low} (and below 2**32), not {number}")
    return number


def _name(what: str, name: str) -> bytes:
    """A topic or md name for libln; a NUL would silently cut it short there."""
    data = name.encode()
    if b"\0" in data:
        raise ValueError(f"{what} {name!r} contains a NUL character")
    return data


class _CallArgs:
    """A port's handle, packet address and size as ctypes objects, and the last timeout."""

    __slots__ = ("handle", "data", "size", "_timeout", "_whole")

    def __init__(self, handle: int, packet: LnStruct) -> None:
        self.handle = ctypes.c_void_p(handle)
        self.data = ctypes.c_void_p(ctypes.addressof(packet))
        self.size = ctypes.c_size_t(ctypes.sizeof(packet))
        self._timeout: tuple[Any, ctypes.c_double] = (None, ctypes.c_double(W.SLICE))
        self._whole: tuple[Any, ctypes.c_double] = (None, ctypes.c_double(-1.0))

    def timeout(self, timeout: float | None) -> ctypes.c_double:
        """The ctypes value of the first libln wait of a write or loan of `timeout`, which
        waits in slices (_waits)."""
        last, value = self._timeout
        if timeout != last:
            value = ctypes.c_double(W.first_slice(timeout))
            self._timeout = (timeout, value)
        return value

    def whole(self, timeout: float | None) -> ctypes.c_double:
        """The ctypes value of a read's `timeout` (None: -1, forever): reads wait once."""
        last, value = self._whole
        if timeout != last:
            value = ctypes.c_double(-1.0 if timeout is None else float(timeout))
            self._whole = (timeout, value)
        return value


class _Port:
    _close_fn: Any = None

    def __init__(self, clnt: client, topic_name: str, md_name: str) -> None:
        self.client = clnt
        self.topic_name = topic_name
        self.message_definition_name = md_name
        self.message_class: type[LnStruct] = message_class(md_name)
        self._packet: LnStruct = self.message_class()
        self._handle: int | None = None
        # One entry per libln call of the port running now: a call appends before it looks
        # at _args and pops after, and close() clears _args before it waits for the deque to
        # be empty, so a port is never freed under a running call (each deque operation is
        # atomic in CPython, and much cheaper than a lock on this hot path).  A second entry
        # means another thread uses the port: refused, as libln allows one thread per port.
        self._calls: deque[None] = deque()
        self._args: _CallArgs | None = None
        # Where libln puts a loaned or borrowed slot's address (one at a time per port).
        self._ptr = ctypes.c_void_p()
        self._ptr_ref = ctypes.byref(self._ptr)
        self._from_address = self.message_class.from_address
        self._close_hooks: list[Callable[[], None]] = []  # its waitset attachments (_handles)

    @property
    def handle(self) -> int:
        if self._handle is None:
            raise ValueError(f"port of topic '{self.topic_name}' is closed")
        return self._handle

    @property
    def packet(self) -> LnStruct:
        """The message write() sends and read() fills; may be replaced by another message
        of the port's md."""
        return self._packet

    @packet.setter
    def packet(self, packet: LnStruct) -> None:
        self._check_message(packet)
        calls = self._calls
        calls.append(None)
        try:
            if len(calls) != 1:
                self._unusable(self)
            self._packet = packet
            a = self._args
            if a is not None:
                a.data = ctypes.c_void_p(ctypes.addressof(packet))
        finally:
            calls.pop()

    def _check_message(self, packet: object) -> None:
        """TypeError unless `packet` is a message of the port's md (also one of a class
        message_class() made again for the same md)."""
        cls, other = self.message_class, type(packet)
        if other is cls or (isinstance(packet, LnStruct) and other.MD_NAME == cls.MD_NAME
                            and getattr(other, "LAYOUT_HASH", None) == cls.LAYOUT_HASH):
            return
        raise TypeError(f"topic '{self.topic_name}' carries {cls.MD_NAME} messages, not "
                        f"{getattr(other, 'MD_NAME', '') or other.__name__}")

    def _unusable(self, args: object) -> NoReturn:
        """Why a call cannot run: ValueError if the port is closed (`args` None), else
        LnBusyError (another thread is in a call of it)."""
        if args is None:
            raise ValueError(f"port of topic '{self.topic_name}' is closed")
        raise ERROR_CLASSES["LnBusyError"](
            f"port of topic '{self.topic_name}' is in use by another thread (libln allows "
            "one thread per port at a time)")

    @contextmanager
    def _call(self) -> Iterator[_CallArgs]:
        """The call arguments for one libln call of the port, which is running while the
        block runs (see _calls); ValueError / LnBusyError as _unusable."""
        a = self._begin()
        try:
            yield a
        finally:
            self._calls.pop()

    def _begin(self) -> _CallArgs:
        """Start one libln call of the port (see _calls) and return its arguments; the
        caller ends the call with `self._calls.pop()` in a `finally`.  ValueError /
        LnBusyError as _unusable, with nothing started."""
        calls = self._calls
        calls.append(None)
        a = self._args
        if a is None or len(calls) != 1:
            calls.pop()
            self._unusable(a)
        return a

    def _wait_idle(self) -> None:
        """Until no call of the port runs in another thread (once _args is None a read ends
        at once, woken by _interrupt, a write or loan within a slice)."""
        while self._calls:
            time.sleep(0.001)

    def _open(self, fn: Any, buffers: int, flags: int, spin_us: int | None = None) -> None:
        opts = C.PortOptions()
        C.ln_port_options_init(ctypes.byref(opts))
        # ctypes would silently keep the low 32 bits of a bigger or negative number
        opts.buffers = _uint32("buffers", buffers, 1)
        opts.flags = flags
        if spin_us is not None:
            opts.spin_us = _uint32("spin_us", spin_us, 0)
        handle = ctypes.c_void_p()
        cls = self.message_class
        fn(self.client.handle, ctypes.byref(handle), _name("topic name", self.topic_name),
           _name("md name", self.message_definition_name), cls.LAYOUT_HASH, ctypes.sizeof(cls),
           ctypes.byref(opts))
        self._handle = handle.value
        # ctypes arguments of the hot path, converted once (halves the cost of a call)
        self._args = _CallArgs(self._handle, self._packet)

    def _interrupt(self, handle: int) -> None:
        """Wake a call of the port that blocks in another thread (a subscriber's read)."""

    def _stop_calls(self) -> None:
        """No new call starts, waitsets let go of the port, a running call ends."""
        self._args = None
        handle = self._handle
        if handle is not None:
            run_close_hooks(self)
            self._interrupt(handle)
        self._wait_idle()

    def _forget(self) -> None:
        self._stop_calls()
        self._handle = None

    def close(self) -> None:
        """Close the port (idempotent).  A read of it blocked in another thread wakes at
        once, a write or loan within 0.1 s; they raise ValueError."""
        self._stop_calls()
        handle, self._handle = self._handle, None
        if handle is None:
            return
        if self in self.client._ports:
            self.client._ports.remove(self)
        type(self)._close_fn(handle)

    def __enter__(self) -> Any:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class publisher(_Port):  # noqa: N801
    _close_fn = staticmethod(C.ln_unpublish)

    def __init__(self, clnt: client, topic_name: str, md_name: str, buffers: int = 1,
                 wait_for_subscribers: bool = False) -> None:
        super().__init__(clnt, topic_name, md_name)
        flags = C.LN_PUBLISH_WAIT_FOR_SUBSCRIBERS if wait_for_subscribers else 0
        self._open(C.ln_publish, buffers, flags)

    def write(self, packet: LnStruct | None = None, timeout: float | None = None) -> None:
        """Publish `packet` (default: self.packet) by copying it into the topic.

        timeout: how long to wait for the write lock or, with wait_for_subscribers, for a
        free buffer (None: forever); LnTimeoutError after it."""
        if packet is not None and packet is not self._packet:
            self._check_message(packet)
        calls = self._calls
        calls.append(None)
        try:
            a = self._args
            if a is None or len(calls) != 1:
                self._unusable(a)
            if packet is None or packet is self._packet:
                _ln_write(a.handle, a.data, a.size, a.timeout(timeout))
            else:
                _ln_write(a.handle, ctypes.addressof(packet), ctypes.sizeof(packet),
                          W.first_slice(timeout))
            return
        except _TimeoutError as exc:
            if not W.waits_longer(timeout):
                raise
            first = exc
        finally:
            calls.pop()
        message = self._packet if packet is None else packet
        self._wait_on(lambda a, t: _ln_write(a.handle, ctypes.addressof(message),
                                             ctypes.sizeof(message), t), timeout, first)

    def _wait_on(self, once: Callable[[_CallArgs, float], Any], timeout: float | None,
                 error: BaseException) -> Any:
        """The further waits of a call that used up its first slice with `error`: `once(args,
        t)` is one libln call that raises LnTimeoutError when its wait `t` passes."""
        deadline = W.deadline(timeout)
        while True:
            t = W.next_slice(deadline)
            if t <= 0:
                raise error
            with self._call() as a:
                try:
                    return once(a, t)
                except _TimeoutError as exc:
                    error = exc

    def loan(self, timeout: float | None = None) -> _Loan:
        """Zero-copy write: `with pub.loan() as msg:` fill msg in place; it is published
        when the block ends normally and dropped if it raises.  The message lives in the
        topic's ring: do not use it after the block.  timeout as write()."""
        return _Loan(self, timeout)

    @property
    def subscriber_count(self) -> int:
        return C.ln_outport_subscriber_count(self.handle)


class subscriber(_Port):  # noqa: N801
    _close_fn = staticmethod(C.ln_unsubscribe)

    def __init__(self, clnt: client, topic_name: str, md_name: str, buffers: int = 1,
                 spin_us: int | None = None, transport: str | None = None) -> None:
        if transport is not None and transport not in _TRANSPORTS:
            raise ValueError(f"transport must be None, {' or '.join(map(repr, _TRANSPORTS))}, "
                             f"not {transport!r}")
        super().__init__(clnt, topic_name, md_name)
        self.buffers = buffers
        self.transport = transport
        self.info = C.SampleInfo()
        flags = 0 if transport is None else _TRANSPORTS[transport]
        self._open(C.ln_subscribe, buffers, flags, spin_us)
        self._info_ref = ctypes.byref(self.info)
        # a blocking read returns LN_EINTR after a signal, so that Python runs its handlers
        C.ln_inport_set_interruptible(self._handle, 1)

    def _interrupt(self, handle: int) -> None:
        C.ln_inport_interrupt(handle)

    def _result(self, rc: int) -> bool:
        if rc in (C.LN_ETIMEOUT, C.LN_EAGAIN):
            return False
        if rc < 0:
            raise error_from_code(rc, C.last_error())
        return True

    def read(self, timeout: float | None = None) -> LnStruct | None:
        """The next sample (copied into self.packet), or None if none came in time.

        timeout None blocks, 0 returns at once.  self.info has seq, timestamp_ns and the
        overruns since the previous read.  One libln wait for the whole time: a signal
        interrupts it, Python runs its handlers and the read goes on for the rest of the
        time, so Ctrl-C ends a blocking read (KeyboardInterrupt; nothing is lost, the next
        read goes on where this one would have).  close() from another thread ends it at
        once with ValueError."""
        start = _monotonic() if timeout else 0.0
        calls = self._calls
        calls.append(None)
        try:
            a = self._args
            if a is None or len(calls) != 1:
                self._unusable(a)
            packet = self._packet  # the one a.data points to
            rc = _ln_read(a.handle, a.data, a.size, a.whole(timeout), self._info_ref)
        finally:
            calls.pop()
        if rc == 0:
            return packet
        if rc == C.LN_EINTR:
            rc, packet = self._read_on(W.end_of(timeout, start))
        return packet if self._result(rc) else None

    async def read_async(self, timeout: float | None = None) -> LnStruct | None:
        """`await sub.read_async(timeout)`: read() without blocking the event loop; waits
        through the loop's waitset (docs/waiting.md)."""
        from ._async_waits import read_async

        return await read_async(self, timeout)

    def __aiter__(self) -> Any:
        """`async for sample in sub`: each sample as read_async() gives it (sub.packet,
        filled again by the next one)."""
        from ._async_waits import samples

        return samples(self)

    def _read_on(self, end: float) -> tuple[int, LnStruct]:
        """Further waits of a read that a signal interrupted (or close() in another thread,
        then ValueError): libln's result and the packet it filled."""
        while True:
            W.run_signal_handlers()  # KeyboardInterrupt for Ctrl-C comes from here
            with self._call() as a:
                packet = self._packet
                rc = _ln_read(a.handle, a.data, a.size, W.remaining(end), self._info_ref)
            if rc != C.LN_EINTR:
                return rc, packet

    def borrow(self, timeout: float | None = None) -> _Borrow:
        """Zero-copy read: `with sub.borrow() as msg:` msg lives in the topic's ring (None if
        nothing came in time); do not use it after the block.  Raises LnOverrunError at the
        end of the block if a publisher overwrote it meanwhile, so what was read from it
        must be discarded.  timeout as read()."""
        return _Borrow(self, timeout)

    def _borrow_on(self, end: float) -> tuple[int, int | None]:
        """Further waits of a borrow that a signal interrupted (as _read_on): libln's
        result and the borrowed slot's address."""
        while True:
            W.run_signal_handlers()
            with self._call() as a:
                rc = _ln_read_borrow(a.handle, self._ptr_ref, W.remaining(end), self._info_ref)
                address = self._ptr.value
            if rc != C.LN_EINTR:
                return rc, address

    @property
    def publisher_count(self) -> int:
        return C.ln_inport_publisher_count(self.handle)

    @property
    def overruns(self) -> int:
        """Samples lost since subscribing (queued mode)."""
        return C.ln_inport_overruns(self.handle)


# The zero-copy blocks are classes rather than generator context managers: a loan or borrow
# then costs about what a copying write or read does for small messages, with the same
# guard against closed ports and concurrent use as every other call (see _Port._calls).

class _Loan:
    """`with pub.loan(timeout) as msg`: loan on enter, commit (or abort on an exception) on
    exit."""

    __slots__ = ("port", "timeout")

    def __init__(self, port: publisher, timeout: float | None) -> None:
        self.port = port
        self.timeout = timeout

    def __enter__(self) -> LnStruct:
        port, timeout = self.port, self.timeout
        a = port._begin()
        try:
            _ln_write_loan(a.handle, port._ptr_ref, a.timeout(timeout))
            return port._from_address(port._ptr.value)
        except _TimeoutError as exc:
            if not W.waits_longer(timeout):
                raise
            first = exc
        finally:
            port._calls.pop()

        def once(a: _CallArgs, t: float) -> LnStruct:
            _ln_write_loan(a.handle, port._ptr_ref, t)
            return port._from_address(port._ptr.value)
        return port._wait_on(once, timeout, first)

    def __exit__(self, exc_type: object, exc: object, tb: object) -> None:
        port = self.port
        a = port._begin()
        try:
            (_ln_write_commit if exc_type is None else _ln_write_abort)(a.handle)
        finally:
            port._calls.pop()


class _Borrow:
    """`with sub.borrow(timeout) as msg`: borrow on enter (msg None if nothing came in
    time), release on exit."""

    __slots__ = ("port", "timeout", "held")

    def __init__(self, port: subscriber, timeout: float | None) -> None:
        self.port = port
        self.timeout = timeout
        self.held = False

    def __enter__(self) -> LnStruct | None:
        port, timeout = self.port, self.timeout
        start = _monotonic() if timeout else 0.0
        a = port._begin()
        try:
            rc = _ln_read_borrow(a.handle, port._ptr_ref, a.whole(timeout), port._info_ref)
            address = port._ptr.value
        finally:
            port._calls.pop()
        if rc == C.LN_EINTR:
            rc, address = port._borrow_on(W.end_of(timeout, start))
        if not port._result(rc):
            return None
        self.held = True
        return port._from_address(address)

    def __exit__(self, exc_type: object, exc: object, tb: object) -> None:
        if not self.held:
            return
        self.held = False
        port = self.port
        a = port._begin()
        try:
            rc = _ln_read_release(a.handle)
        finally:
            port._calls.pop()
        if rc < 0 and exc_type is None:
            raise error_from_code(rc, C.last_error())
