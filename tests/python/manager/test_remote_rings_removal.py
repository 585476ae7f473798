"""RemoteRings (manager/registry/rings.py) when its daemon dies under a removal: a segment whose
removal fails because the connection is gone, before the host is marked unreachable, is
removed at the next resync instead of being forgotten in that host's /dev/shm (found by
the crash-injection driver, tests/python/robustness)."""

from __future__ import annotations

import asyncio

from links_and_nodes.manager.registry.rings import RemoteRings


class Link:
    """A daemon link that records removals, or fails them like a closed connection."""

    def __init__(self, dead: bool) -> None:
        self.dead = dead
        self.removed: list[str] = []

    async def ring_create(self, *args: object, adopt: bool = False) -> None:
        if self.dead:
            raise ConnectionError("connection closed by the daemon")

    async def ring_set_counts(self, *args: object) -> None:
        pass

    async def ring_release_reader(self, *args: object) -> None:
        pass

    async def ring_remove(self, name: str) -> None:
        if self.dead:
            raise ConnectionError("connection closed by the daemon")
        self.removed.append(name)


def test_removal_on_a_dead_connection_is_done_at_the_resync() -> None:
    async def scenario() -> tuple[list[str], list[str]]:
        rings = RemoteRings("b", "inst", "h2")
        rings.link = Link(dead=False)  # type: ignore[assignment]
        name = await rings.create(1, "t", "md", 1, 8, 4)
        rings.link = Link(dead=True)  # type: ignore[assignment]
        gone = await rings.remove(1)
        assert gone == [name]
        back = Link(dead=False)
        rings.link = back  # type: ignore[assignment]
        await rings.resync(timeout=1.0)
        return [name], back.removed

    made, removed = asyncio.run(scenario())
    assert removed == made
