"""asyncio on libln's waitset against a real manager: sub.read_async() and `async for`,
client.wait_publisher(), service.call_async() and client.provide_async() (an async handler
that awaits other things while its caller waits); cancelling any waiting task leaves no
attachment in the loop's waitset; close() from another thread or from the loop ends what
waits on the closed thing."""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

import pytest
from topics.conftest import Manager

import links_and_nodes as ln
from links_and_nodes._async_waits import loop_waitset

REPO = Path(__file__).resolve().parents[3]
LIMIT = 60.0  # seconds: an upper bound against hangs, never a pass criterion
MD = "robot/joint_state"

ln.add_message_definition_dir(REPO / "tests" / "fixtures" / "md" / "services")


def run(main: Callable[[], Awaitable[Any]]) -> Any:
    """asyncio.run(main()), failing after LIMIT instead of hanging."""
    async def bounded() -> Any:
        return await asyncio.wait_for(main(), LIMIT)
    return asyncio.run(bounded())


def attached() -> list[str]:
    """What the running loop's waitset has attached (its `what`s)."""
    return [attachment.what for attachment in loop_waitset().waitset.attachments]


async def until(predicate: Callable[[], object], what: str) -> None:
    """Let the loop run until `predicate()` holds (bounded by run()'s LIMIT)."""
    while not predicate():
        await asyncio.sleep(0.001)


def test_read_async_and_async_for(manager: Manager) -> None:
    with manager.client() as clnt:
        sub = clnt.subscribe("a.data", MD, buffers=16)
        pub = clnt.publish("a.data", MD)

        def write(cycle: int) -> None:
            pub.packet.cycle = cycle
            pub.write()

        async def main() -> list[int]:
            loop = asyncio.get_running_loop()
            assert await sub.read_async(timeout=0) is None
            assert await sub.read_async(timeout=0.01) is None
            assert attached() == []
            loop.call_later(0.01, write, 1)  # from the loop itself, while read_async waits
            sample = await sub.read_async(timeout=LIMIT)
            assert sample is not None and sample.cycle == 1
            assert attached() == []
            # from another thread, one after the other, while `async for` waits
            writer = threading.Thread(target=lambda: [write(c) for c in range(2, 7)])
            writer.start()
            seen = []
            async for sample in sub:
                seen.append(sample.cycle)
                if sample.cycle == 6:
                    break
            writer.join(LIMIT)
            return seen

        assert run(main) == [2, 3, 4, 5, 6]


def test_wait_publisher(manager: Manager) -> None:
    with manager.client() as clnt:
        sub = clnt.subscribe("a.alive", MD)

        async def main() -> None:
            assert await clnt.wait_publisher(sub, timeout=0.01) is False
            waiting = asyncio.create_task(clnt.wait_publisher("a.alive"))
            await until(lambda: attached() == ["subscriber"], "the wait to attach")
            assert not waiting.done()
            with manager.client("other") as other:
                other.publish("a.alive", MD)
                assert await waiting is True
                assert attached() == []
                assert await clnt.wait_publisher(sub) is True  # has one already
                # a topic this client does not subscribe: subscribed for the wait
                other.publish("a.other", MD)
                assert await clnt.wait_publisher("a.other", MD, timeout=LIMIT) is True
            with pytest.raises(ValueError, match="md_name"):
                await clnt.wait_publisher("a.unknown")
            assert attached() == []

        run(main)
        assert [port.topic_name for port in clnt._ports] == ["a.alive"]


def test_cancelled_waits_leave_no_attachment(manager: Manager) -> None:
    with manager.client() as clnt:
        data = clnt.subscribe("a.cancel", MD)
        alive = clnt.subscribe("a.cancel_alive", MD)

        async def iterate() -> None:
            async for _sample in data:
                pass

        async def main() -> None:
            tasks = [asyncio.create_task(coro) for coro in (
                data.read_async(), data.read_async(timeout=LIMIT), iterate(),
                clnt.wait_publisher(alive, timeout=LIMIT))]
            # the three waits on `data` share one attachment
            await until(lambda: sorted(attached()) == ["subscriber"] * 2, "the waits")
            await asyncio.sleep(0.01)
            assert not any(task.done() for task in tasks)
            for task in tasks:
                task.cancel()
            results = await asyncio.gather(*tasks, return_exceptions=True)
            assert all(isinstance(r, asyncio.CancelledError) for r in results), results
            assert attached() == []
            assert loop_waitset().waitset.next_due() is None

        run(main)


def test_close_from_another_thread_ends_read_async(manager: Manager) -> None:
    with manager.client() as clnt:
        sub = clnt.subscribe("a.close", MD)

        async def main() -> None:
            reading = asyncio.create_task(sub.read_async())
            await until(lambda: attached() == ["subscriber"], "the read to attach")
            closer = threading.Thread(target=sub.close)
            closer.start()
            with pytest.raises(ValueError, match="closed"):
                await reading
            closer.join(LIMIT)
            assert attached() == []

        run(main)


def echo_request(seq: int, text: str) -> dict[str, Any]:
    return {"caller": 1, "seq": seq, "delay_us": 0, "text": text}


def test_provide_async_answers_while_the_loop_runs(manager: Manager) -> None:
    """The handler awaits a sample that another task publishes only once the handler has
    started: the loop serves everything else while a request is handled."""
    with manager.client("provider") as clnt, manager.client("caller") as caller:
        sub = clnt.subscribe("a.go", MD, buffers=4)
        pub = caller.publish("a.go", MD)
        started = 0

        async def handler(request: ln.service_request) -> Any:
            nonlocal started
            started += 1
            req = request.req
            if req.text == "fail":
                raise RuntimeError("asked to fail")
            if req.text == "respond":
                request.respond({"seq": req.seq, "text": "answered myself"})
                return None
            sample = await sub.read_async(timeout=LIMIT)
            assert sample is not None
            return {"caller": req.caller, "seq": req.seq * 10 + sample.cycle, "text": req.text}

        async def main() -> None:
            provider = clnt.provide_async("a.echo", "lntest/echo", handler)
            assert provider.group == "asyncio.a.echo"
            assert attached() == ["provider"]
            svc = caller.get_service("a.echo", "lntest/echo")
            call = asyncio.create_task(svc.call_async(echo_request(4, "wait"), LIMIT))
            await until(lambda: started == 1, "the handler to start")
            assert not call.done()
            pub.packet.cycle = 2
            pub.write()
            resp = await call
            assert (resp.seq, resp.text) == (42, "wait")
            assert svc.resp.seq == 0  # call_async answers with a struct of its own
            resp = await svc.call_async(echo_request(5, "respond"), LIMIT)
            assert (resp.seq, resp.text) == (5, "answered myself")
            with pytest.raises(ln.LnServiceError, match="RuntimeError: asked to fail"):
                await svc.call_async(echo_request(6, "fail"), LIMIT)
            # several tasks on one handle: serialized, each gets its own response
            pub.packet.cycle = 1
            pub.write()
            pub.write()
            both = await asyncio.gather(svc.call_async(echo_request(7, "a"), LIMIT),
                                        svc.call_async(echo_request(8, "b"), LIMIT))
            assert [(r.seq, r.text) for r in both] == [(71, "a"), (81, "b")]
            await until(lambda: attached() == ["provider"], "listening again")
            provider.close()
            assert attached() == []

        run(main)


@pytest.mark.parametrize("close", ["provider", "client"])
def test_closing_an_async_provider_during_a_request(manager: Manager, close: str) -> None:
    """close() on the loop while the handler waits: the caller gets an error answer, the
    coroutine is cancelled, nothing deadlocks (also through the client's close())."""
    clnt = manager.client("provider")
    started: list[bool] = []
    cancelled: list[bool] = []

    async def handler(request: ln.service_request) -> None:
        started.append(True)
        try:
            await asyncio.Event().wait()  # never set
        except asyncio.CancelledError:
            cancelled.append(True)
            raise

    async def main() -> None:
        with manager.client("caller") as caller:
            provider = clnt.provide_async("a.stuck", "lntest/echo", handler)
            svc = caller.get_service("a.stuck", "lntest/echo")
            call = asyncio.create_task(svc.call_async(echo_request(1, "x"), LIMIT))
            await until(lambda: started, "the handler to start")
            assert attached() == []  # the group is detached while a job handles it
            (provider if close == "provider" else clnt).close()
            with pytest.raises(ln.LnError) as err:
                await call
            assert isinstance(err.value, ln.LnServiceError | ln.LnConnectionError), err
            await until(lambda: cancelled, "the coroutine to be cancelled")
            assert attached() == []

    try:
        run(main)
    finally:
        clnt.close()
