"""asyncio on libln's waitset: one hidden WaitSet per event loop, whose descriptor the loop
watches (loop.add_reader) and whose next timer or deadline it schedules (loop.call_at);
what the waitset reports wakes the coroutines waiting for it.  No thread, no polling.

On it: subscriber.read_async() and `async for sample in sub`, client.wait_publisher(),
service.call_async() (a blocking call in the loop's default executor: libln has no
non-blocking call).  client.provide_async() is in _async_provider.py.  A coroutine is
attached only while it waits: cancelled or not, it leaves no attachment behind
(docs/waiting.md, "Python and asyncio")."""

from __future__ import annotations

import asyncio
import contextlib
import time
import weakref
from collections.abc import AsyncIterator, Iterator
from typing import TYPE_CHECKING, Any

from ._waitset import Attachment, WaitEvent, WaitSet

if TYPE_CHECKING:
    from ._client import client, subscriber
    from ._services import service
    from .md_types import LnStruct

__all__ = ["LoopWaitSet", "call_async", "loop_waitset", "read_async", "samples",
           "wait_publisher"]

_loops: weakref.WeakKeyDictionary[asyncio.AbstractEventLoop, LoopWaitSet] = \
    weakref.WeakKeyDictionary()


def loop_waitset(loop: asyncio.AbstractEventLoop | None = None) -> LoopWaitSet:
    """The waitset of `loop` (default: the running one), made on first use."""
    if loop is None:
        loop = asyncio.get_running_loop()
    found = _loops.get(loop)
    if found is None:
        found = _loops[loop] = LoopWaitSet(loop)
    return found


class LoopWaitSet:
    """A WaitSet driven by an asyncio loop: each attachment's `user` is the callback that
    gets its WaitEvents, on the loop's thread."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        self._loop = weakref.ref(loop)  # the loop keys _loops: never keep it alive
        self.waitset = WaitSet()
        self._fd = self.waitset.fileno()
        self._due: asyncio.TimerHandle | None = None
        self._due_ns: int | None = None
        self._watches: dict[tuple[int, bool], _Watch] = {}
        loop.add_reader(self._fd, self.collect)

    @property
    def loop(self) -> asyncio.AbstractEventLoop:
        loop = self._loop()
        if loop is None:
            raise RuntimeError("the event loop of this waitset is gone")
        return loop

    def attach(self, attach: Any, **options: Any) -> Attachment:
        """`attach(WaitSet, ..., user=callback, **options)`, e.g. WaitSet.attach_provider, on
        this loop's waitset; the callback runs on the loop for each of its events."""
        attachment: Attachment = attach(self.waitset, **options)
        self.schedule()
        return attachment

    def collect(self) -> None:
        """Take every ready event (without sleeping) and hand each to its callback."""
        waitset = self.waitset
        while True:
            events = waitset.wait(0)
            for event in events:
                self._dispatch(event)
            if len(events) < waitset.capacity:
                break
        self.schedule()

    def _dispatch(self, event: WaitEvent) -> None:
        callback = None if event.attachment is None else event.attachment.data
        if callback is None:
            return
        try:
            callback(event)
        except Exception as exc:  # noqa: BLE001 - one callback must not starve the others
            self.loop.call_exception_handler({
                "message": f"links_and_nodes: callback of {event.attachment!r} failed",
                "exception": exc})

    def schedule(self) -> None:
        """Have the loop collect when the waitset's next timer or deadline falls due."""
        due = self.waitset.next_due()
        if due == self._due_ns and self._due is not None:
            return
        if self._due is not None:
            self._due.cancel()
            self._due = None
        self._due_ns = due
        if due is not None:
            loop = self.loop
            delay = (due - time.monotonic_ns()) / 1e9
            self._due = loop.call_at(loop.time() + max(delay, 0.0), self._on_due)

    def _on_due(self) -> None:
        self._due = None
        self._due_ns = None
        self.collect()

    @contextlib.contextmanager
    def watching(self, sub: subscriber, liveliness: bool, waiter: _Waiter) -> Iterator[None]:
        """`waiter` is woken by the DATA (or, with `liveliness`, GONE/BACK) events of `sub`
        while the block runs; the subscriber is attached while anyone watches it."""
        key = (id(sub), liveliness)
        watch = self._watches.get(key)
        if watch is None:
            watch = self._watches[key] = _Watch(self, sub, liveliness)
        watch.waiters.add(waiter)
        try:
            yield
        finally:
            watch.waiters.discard(waiter)
            if not watch.waiters:
                del self._watches[key]
                watch.end()


class _Waiter:
    """One waiting coroutine: next() returns True when woken, False at its deadline."""

    def __init__(self, loop: asyncio.AbstractEventLoop, timeout: float | None) -> None:
        self.loop = loop
        self.end = None if timeout is None or timeout < 0 else loop.time() + timeout
        self.future: asyncio.Future[bool] | None = None

    def wake(self, woken: bool = True) -> None:
        future = self.future
        if future is not None and not future.done():
            future.set_result(woken)

    async def next(self) -> bool:
        timer = None
        if self.end is not None:
            if self.loop.time() >= self.end:
                return False
            timer = self.loop.call_at(self.end, self.wake, False)
        self.future = self.loop.create_future()
        try:
            return await self.future
        finally:
            self.future = None
            if timer is not None:
                timer.cancel()


class _Watch:
    """The loop waitset's attachment of one subscriber, shared by its waiters.  A close of
    the subscriber (in any thread) detaches it and wakes them, so that their next read
    raises ValueError."""

    def __init__(self, owner: LoopWaitSet, sub: subscriber, liveliness: bool) -> None:
        self.owner = owner
        self.sub = sub
        self.waiters: set[_Waiter] = set()
        self.attachment = owner.attach(WaitSet.attach_subscriber, sub=sub, data=not liveliness,
                                       liveliness=liveliness, user=self._fire)
        sub._close_hooks.append(self._closing)

    def _fire(self, _event: WaitEvent | None = None) -> None:
        for waiter in list(self.waiters):
            waiter.wake()

    def _closing(self) -> None:
        with contextlib.suppress(RuntimeError):  # a closed loop: nobody waits any more
            self.owner.loop.call_soon_threadsafe(self._fire)

    def end(self) -> None:
        with contextlib.suppress(ValueError):
            self.sub._close_hooks.remove(self._closing)
        self.attachment.detach()


# ---- subscribers ----------------------------------------------------------------------------
async def read_async(sub: subscriber, timeout: float | None = None) -> LnStruct | None:
    """subscriber.read_async: the next sample (in sub.packet), or None after `timeout`."""
    packet = sub.read(timeout=0)
    if packet is not None or timeout == 0:
        return packet
    loop = asyncio.get_running_loop()
    waiter = _Waiter(loop, timeout)
    with loop_waitset(loop).watching(sub, False, waiter):
        while True:
            packet = sub.read(timeout=0)  # also what came before the attachment
            if packet is not None:
                return packet
            if not await waiter.next():
                return None


async def samples(sub: subscriber) -> AsyncIterator[LnStruct]:
    """`async for sample in sub`: every sample as read() gives it (sub.packet, filled
    again by the next one), forever."""
    while True:
        packet = await read_async(sub)
        if packet is not None:
            yield packet


async def wait_publisher(sub: subscriber, timeout: float | None = None) -> bool:
    """Until `sub`'s topic has a publisher: True, or False after `timeout`."""
    if sub.publisher_count > 0:
        return True
    loop = asyncio.get_running_loop()
    waiter = _Waiter(loop, timeout)
    with loop_waitset(loop).watching(sub, True, waiter):
        while True:
            if sub.publisher_count > 0:  # also one that came before the attachment
                return True
            if not await waiter.next():
                return False


async def wait_topic_publisher(clnt: client, topic: Any, md_name: str | None,
                               timeout: float | None) -> bool:
    """client.wait_publisher: `topic` is a subscriber or a topic name (of a subscriber of
    `clnt`, else one subscribed for the wait, with md `md_name`)."""
    from ._client import subscriber

    if isinstance(topic, subscriber):
        return await wait_publisher(topic, timeout)
    mine = next((port for port in clnt._ports if isinstance(port, subscriber)
                 and port.topic_name == topic and port._handle is not None), None)
    if mine is not None:
        return await wait_publisher(mine, timeout)
    if md_name is None:
        raise ValueError(f"client '{clnt.name}' has no subscriber of '{topic}': pass its "
                         "md_name (or a subscriber)")
    with clnt.subscribe(topic, md_name) as sub:
        return await wait_publisher(sub, timeout)


# ---- services -------------------------------------------------------------------------------
async def call_async(svc: service, request: Any, timeout: float | None) -> Any:
    """service.call_async: the call runs in the loop's default executor; a cancelled
    caller stops waiting at once, the call itself ends in its thread (by `timeout`)."""
    loop = asyncio.get_running_loop()
    return await loop.run_in_executor(None, svc._call_with, request, timeout)
