"""What the Python objects that own a libln service or event handle have in common: the
handle (ValueError once closed), close() that is idempotent and forgets the object in its
client, `with` support, and the bookkeeping of a handler running in libln's callback.

Callers (`service`, `event`) serialize their calls on a lock and are kept in
`client._services`; handlers (`provided_service`, `event_handler`) run in the thread that
handles their group and are kept in `client._providers`.  The client forgets (`_forget`)
every handle it destroys with itself.  Before a handle is freed, its close hooks run
(run_close_hooks): they end its waitset attachments (_waitset.py) first."""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ._client import client

# Per thread: the clients whose handlers run on this thread's stack (handling), whether it
# waits in wait_and_handle_service_group_requests (waiting) and a BaseException a handler
# raised there, to be raised again by that wait (pending).
thread_state = threading.local()


def run_close_hooks(obj: Any) -> None:
    """Run (and drop) the close hooks of `obj`, a port, provider, parameter block or client
    about to be freed: each ends a waitset attachment of it, also from another thread than
    the one that waits."""
    hooks: list[Callable[[], None]] = obj._close_hooks
    while hooks:
        try:
            hook = hooks.pop()
        except IndexError:  # another thread closing it too took the last one
            return
        hook()


@contextmanager
def handling(clnt: client) -> Iterator[None]:
    """Marks `clnt` as running a handler on this thread while the block runs."""
    stack = getattr(thread_state, "handling", None)
    if stack is None:
        stack = thread_state.handling = []
    stack.append(clnt)
    try:
        yield
    finally:
        stack.pop()


class _Owned:
    """A libln handle named `what` ("service 'x'") that this object owns."""

    _what = "handle"

    def __init__(self, clnt: client, name: str, md_name: str) -> None:
        self.client = clnt
        self.name = name
        self.message_definition_name = md_name
        self._handle: int | None = None
        self._close_hooks: list[Callable[[], None]] = []

    @property
    def handle(self) -> int:
        if self._handle is None:
            raise ValueError(f"{self._what} '{self.name}' is closed")
        return self._handle

    def __enter__(self) -> Any:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        raise NotImplementedError


class CallerHandle(_Owned):
    """A service or event that this client calls; calls on it are serialized."""

    def __init__(self, clnt: client, name: str, md_name: str) -> None:
        super().__init__(clnt, name, md_name)
        self._lock = threading.Lock()

    def _release(self, handle: int) -> None:
        raise NotImplementedError

    def _forget(self) -> None:
        with self._lock:
            self._handle = None

    def close(self) -> None:
        """Release the handle (idempotent); the results of earlier calls stay readable."""
        with self._lock:
            if self._handle is None:
                return
            handle, self._handle = self._handle, None
        if self in self.client._services:
            self.client._services.remove(self)  # type: ignore[arg-type]
        self._release(handle)


class HandlerHandle(_Owned):
    """A service provider or event handler of this client."""

    def __init__(self, clnt: client, name: str, md_name: str, group: str | None) -> None:
        super().__init__(clnt, name, md_name)
        self.group = group

    def _release(self, handle: int) -> None:
        raise NotImplementedError

    def _forget(self) -> None:
        run_close_hooks(self)
        self._handle = None

    def close(self) -> None:
        """Unregister (idempotent).  Waits for a handler of it running in another thread;
        from inside one of its own handlers it raises LnBusyError."""
        if self._handle is None:
            return
        run_close_hooks(self)
        self._release(self._handle)
        self._handle = None
        if self in self.client._providers:
            self.client._providers.remove(self)  # type: ignore[arg-type]


def keep_for_wait(exc: BaseException, what: str) -> None:
    """A KeyboardInterrupt/SystemExit that handler `what` raised: kept for the
    wait_and_handle_service_group_requests this thread is in, which raises it again; in a
    thread pool's thread it cannot be raised anywhere, so it is logged."""
    if isinstance(exc, Exception):
        return
    if getattr(thread_state, "waiting", False):
        thread_state.pending = exc
    else:
        logging.getLogger("links_and_nodes.services").warning(
            "%s: %s in a handler of a thread pool; it cannot be raised there", what,
            type(exc).__name__)
