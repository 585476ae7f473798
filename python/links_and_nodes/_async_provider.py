"""client.provide_async: a service provider whose handler is a coroutine, run on the event
loop.

libln answers a request only inside the handler call it makes, and that call must not block
the loop.  So the provider's service group is attached to the loop's waitset; when it has
requests, one job in the loop's default executor handles them
(wait_and_handle_service_group_requests(group, 0)), and for each request the handler call
in that thread runs the coroutine on the loop (run_coroutine_threadsafe) and waits for it,
then answers.  The coroutine may await anything, meanwhile the loop serves everything
else; the requests of one provider are handled one after the other.  While a job runs the
group is detached (it would be reported again and again), and attached again after."""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import inspect
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any

from ._services import provided_service, service_request, wait_and_handle
from ._waitset import Attachment, WaitEvent, WaitSet

if TYPE_CHECKING:
    from ._client import client

__all__ = ["AsyncHandler", "async_provided_service"]

# handler(request) -> awaitable of None (it answered with request.respond...) or of the
# response (a response struct or a dict of its fields)
AsyncHandler = Callable[[service_request], Awaitable[Any]]


class async_provided_service(provided_service):  # noqa: N801 - like provided_service
    """A provided service whose `async_handler(request)` runs on `loop` (made by
    client.provide_async).  It answers with request.respond()/respond_error() or returns
    the response; an exception becomes an error response as for provided_service.  close()
    (or the client's) from any thread, also the loop's while a request is being handled:
    that request is then answered with an error and its coroutine cancelled."""

    def __init__(self, clnt: client, name: str, md_name: str, handler: AsyncHandler,
                 group: str | None, max_size: int | None,
                 loop: asyncio.AbstractEventLoop) -> None:
        self.async_handler = handler
        self.loop = loop
        # set when closing: a handler call stops waiting for its coroutine
        self._stop: concurrent.futures.Future[None] = concurrent.futures.Future()
        self._attachment: Attachment | None = None
        self._job: asyncio.Future[None] | None = None
        super().__init__(clnt, name, md_name, self._bridge,
                         f"asyncio.{name}" if group is None else group, max_size)
        self._close_hooks.append(self._closing)
        try:
            self._listen()
        except BaseException:
            self.close()
            raise

    def _listen(self) -> None:
        from ._async_waits import loop_waitset

        self._attachment = loop_waitset(self.loop).attach(
            WaitSet.attach_provider, provider=self, user=self._on_requests)

    def _on_requests(self, _event: WaitEvent) -> None:
        """On the loop: the group has requests; hand them to a job."""
        if self._attachment is not None:
            self._attachment.detach()
            self._attachment = None
        if self._job is None and self._handle is not None:
            self._job = self.loop.run_in_executor(None, self._handle_requests)
            self._job.add_done_callback(self._handled)

    def _handle_requests(self) -> None:
        """In the executor: every request that is ready, until none is."""
        while self._handle is not None and not self._stop.done():
            if wait_and_handle(self.client, self.group, 0) == 0:
                return

    def _handled(self, job: asyncio.Future[None]) -> None:
        self._job = None
        if self._handle is None or self._stop.done():
            return
        exc = None if job.cancelled() else job.exception()
        if exc is not None:
            self.loop.call_exception_handler({
                "message": f"links_and_nodes: handling requests of service '{self.name}' "
                           "failed", "exception": exc})
        self._listen()

    def _bridge(self, request: service_request) -> None:
        """libln's handler call (in the executor): run the coroutine on the loop, wait for
        it (or for close()) and answer with what it returned."""
        if self._stop.done():
            raise RuntimeError(f"service '{self.name}' is being closed")
        future = asyncio.run_coroutine_threadsafe(self._serve(request), self.loop)
        concurrent.futures.wait([future, self._stop],
                                return_when=concurrent.futures.FIRST_COMPLETED)
        if not future.done():
            future.cancel()
            raise RuntimeError(f"service '{self.name}' was closed during the call")
        # A cancelled coroutine (the loop ended) or a KeyboardInterrupt in it becomes an
        # error response; raised as is, wait_and_handle would raise it again in this thread.
        if future.cancelled():
            raise RuntimeError(f"handler of service '{self.name}' was cancelled")
        exc = future.exception()
        if exc is not None and not isinstance(exc, Exception):
            raise RuntimeError(f"handler of service '{self.name}' did not finish: "
                               f"{type(exc).__name__}") from exc
        response = future.result()
        if response is not None and not request.responded:
            request.respond(response)

    async def _serve(self, request: service_request) -> Any:
        result = self.async_handler(request)
        return await result if inspect.isawaitable(result) else result

    def _closing(self) -> None:
        with contextlib.suppress(concurrent.futures.InvalidStateError):
            self._stop.set_result(None)
