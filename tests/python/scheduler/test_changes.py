"""The scheduler's change notification (manager/processes/changes.py): one notify wakes every waiter
in the same turn of the event loop, waiters whose condition does not hold yet wait on, an
exception of the condition ends the wait, and a cancelled or timed-out waiter is not kept."""

from __future__ import annotations

import asyncio

import pytest

from links_and_nodes.manager.processes.changes import Changes


def test_one_notify_wakes_every_waiter_at_once() -> None:
    async def main() -> list[int]:
        changes = Changes()
        state = {"n": 0}
        woke: list[int] = []

        async def waiter(i: int) -> None:
            await changes.wait_for(lambda: state["n"] >= 1)
            woke.append(i)

        tasks = [asyncio.create_task(waiter(i)) for i in range(50)]
        await asyncio.sleep(0)  # every waiter is waiting now
        assert woke == []
        state["n"] = 1
        changes.notify()
        # one turn of the loop (a lock handed from waiter to waiter would need 50)
        await asyncio.sleep(0)
        seen = list(woke)
        await asyncio.gather(*tasks)
        return seen

    assert sorted(asyncio.run(main())) == list(range(50))


def test_a_waiter_whose_condition_does_not_hold_waits_on() -> None:
    async def main() -> None:
        changes = Changes()
        state = {"n": 0}
        task = asyncio.create_task(changes.wait_for(lambda: state["n"] == 2))
        for n in (1, 3, 2):
            await asyncio.sleep(0)
            assert not task.done(), n
            state["n"] = n
            changes.notify()
        await asyncio.wait_for(task, 5)

    asyncio.run(main())


def test_an_exception_of_the_condition_ends_the_wait() -> None:
    async def main() -> None:
        changes = Changes()
        failed = {"yes": False}

        def condition() -> bool:
            if failed["yes"]:
                raise RuntimeError("dependency failed")
            return False

        task = asyncio.create_task(changes.wait_for(condition))
        await asyncio.sleep(0)
        failed["yes"] = True
        changes.notify()
        with pytest.raises(RuntimeError, match="dependency failed"):
            await asyncio.wait_for(task, 5)

    asyncio.run(main())


def test_a_timed_out_waiter_is_not_kept() -> None:
    async def main() -> None:
        changes = Changes()
        with pytest.raises(TimeoutError):
            await asyncio.wait_for(changes.wait_for(lambda: False), 0.01)
        assert changes._waiters == []

    asyncio.run(main())


def test_a_condition_true_at_once_does_not_wait() -> None:
    async def main() -> None:
        changes = Changes()
        await asyncio.wait_for(changes.wait_for(lambda: True), 5)
        assert changes._waiters == []

    asyncio.run(main())
