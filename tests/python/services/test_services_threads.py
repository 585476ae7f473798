"""Service groups handled by libln's thread pools, with Python handlers and several Python
callers at once.  Concurrency is shown by a barrier that only opens when enough handlers
run at the same time, never by timing."""

from __future__ import annotations

import contextlib
import threading
from concurrent.futures import ThreadPoolExecutor

import pytest

import links_and_nodes as ln

from .conftest import LIMIT, Manager, serving


class gate:  # noqa: N801
    """A handler that waits until `width` handlers are inside at once, and records the most
    that ever were, and which threads ran it."""

    def __init__(self, width: int) -> None:
        self.barrier = threading.Barrier(width, timeout=LIMIT)
        self.lock = threading.Lock()
        self.inside = 0
        self.most = 0
        self.threads: set[int] = set()

    def __call__(self, request: ln.service_request) -> None:
        with self.lock:
            self.inside += 1
            self.most = max(self.most, self.inside)
            self.threads.add(threading.get_ident())
        try:
            self.barrier.wait()  # BrokenBarrierError (an error response) if alone too long
        finally:
            with self.lock:
                self.inside -= 1
        request.respond({"values": request.req.values * request.req.factor})


def call_in_threads(clnt: ln.client, name: str, n: int) -> list[list[float]]:
    """n calls at once, each from its own thread with its own handle."""
    handles = [clnt.get_service(name, "lntest/scale") for _ in range(n)]
    for i, svc in enumerate(handles):
        svc.req.values = [float(i), 1.0]
        svc.req.factor = 2.0

    def call(svc: ln.service) -> list[float]:
        return svc.call(timeout=LIMIT).values.tolist()

    with ThreadPoolExecutor(n) as pool:
        return list(pool.map(call, handles))


def test_pool_runs_handlers_concurrently(manager: Manager) -> None:
    handler = gate(3)
    with manager.client("provider") as prov_c, manager.client("callers") as call_c:
        prov_c.get_service_provider("math.scale", "lntest/scale", handler)
        prov_c.set_max_threads("workers", 3)
        prov_c.handle_service_group_in_thread_pool(None, "workers")
        results = call_in_threads(call_c, "math.scale", 3)
    assert results == [[2.0 * i, 2.0] for i in range(3)]
    assert handler.most == 3
    assert len(handler.threads) == 3
    assert threading.get_ident() not in handler.threads


def test_pool_size_limits_concurrency(manager: Manager) -> None:
    handler = gate(2)  # pairs of handlers pass; a third one at once would be too many
    with manager.client("provider") as prov_c, manager.client("callers") as call_c:
        prov_c.get_service_provider("math.scale", "lntest/scale", handler, group="g")
        prov_c.set_max_threads("pair", 2)
        prov_c.handle_service_group_in_thread_pool("g", "pair")
        results = call_in_threads(call_c, "math.scale", 6)
    assert results == [[2.0 * i, 2.0] for i in range(6)]
    assert handler.most == 2


def test_groups_are_handled_separately(manager: Manager) -> None:
    """A group in a pool is no longer handled by wait_and_handle; another group still is."""
    def scale(request: ln.service_request) -> None:
        request.respond({"values": request.req.values * request.req.factor})

    with manager.client("provider") as prov_c, manager.client("callers") as call_c:
        prov_c.get_service_provider("pooled", "lntest/scale", scale, group="pooled")
        prov_c.get_service_provider("waited", "lntest/scale", scale, group="waited")
        prov_c.handle_service_group_in_thread_pool("pooled", "single")
        with pytest.raises(ln.LnBusyError):
            prov_c.wait_and_handle_service_group_requests("pooled", timeout=0)
        assert call_in_threads(call_c, "pooled", 2) == [[0.0, 2.0], [2.0, 2.0]]
        with serving(prov_c, "waited") as counts:
            assert call_in_threads(call_c, "waited", 2) == [[0.0, 2.0], [2.0, 2.0]]
        assert sum(counts) == 2


def test_keyboard_interrupt_in_a_handler_reaches_the_waiting_thread(manager: Manager) -> None:
    def handler(request: ln.service_request) -> None:
        raise KeyboardInterrupt

    with manager.client("provider") as prov_c, manager.client("caller") as call_c:
        prov_c.get_service_provider("math.scale", "lntest/scale", handler)
        svc = call_c.get_service("math.scale", "lntest/scale")
        errors: list[BaseException] = []

        def call() -> None:
            try:
                svc.call(timeout=LIMIT)
            except BaseException as exc:  # noqa: BLE001
                errors.append(exc)

        caller = threading.Thread(target=call)
        caller.start()
        with pytest.raises(KeyboardInterrupt):
            prov_c.wait_and_handle_service_group_requests(timeout=LIMIT)
        caller.join(LIMIT)
        assert len(errors) == 1 and isinstance(errors[0], ln.LnServiceError)
        assert "KeyboardInterrupt" in str(errors[0])


def test_close_ends_a_wait_in_another_thread(manager: Manager) -> None:
    clnt = manager.client("provider")
    clnt.get_service_provider("math.scale", "lntest/scale", lambda r: r.respond())
    outcome: list[object] = []
    started = threading.Event()

    def wait() -> None:
        started.set()
        try:
            outcome.append(clnt.wait_and_handle_service_group_requests(timeout=None))
        except BaseException as exc:  # noqa: BLE001 - checked below
            outcome.append(exc)

    waiter = threading.Thread(target=wait, daemon=True)
    waiter.start()
    started.wait(LIMIT)
    clnt.close()  # before or during the wait: either way it must not run on a freed client
    waiter.join(LIMIT)
    assert not waiter.is_alive(), "wait_and_handle_service_group_requests still blocks"
    assert len(outcome) == 1 and isinstance(outcome[0], ValueError), outcome


@pytest.mark.parametrize("pool", [False, True])
def test_close_inside_a_handler_is_refused(manager: Manager, pool: bool) -> None:
    with manager.client("provider") as prov_c, manager.client("caller") as call_c:
        def handler(request: ln.service_request) -> None:
            prov_c.close()

        prov_c.get_service_provider("math.scale", "lntest/scale", handler)
        if pool:
            prov_c.handle_service_group_in_thread_pool(None, "workers")
        svc = call_c.get_service("math.scale", "lntest/scale")
        with (contextlib.nullcontext() if pool else serving(prov_c)):
            for _ in range(2):  # the provider, and the client, go on serving
                with pytest.raises(ln.LnServiceError, match="LnBusyError"):
                    svc.call(timeout=LIMIT)
