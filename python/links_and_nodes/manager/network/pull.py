"""Pull topics of a manager (docs/pull.md): each topic that the `topics` sections give
`pull:ndn-udp` is served by the ln_daemon of every host with a publisher of it, which
answers NDN Interests for it from the topic's ring.  This module follows the registry (as
the loggers do), tells those daemons, retries a refusal until it goes through, removes a
topic whose publishers left, and gathers the producers' counters for the network view."""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..config import model
from ..config.pull_settings import pull_uri
from ..loggers.loggers import Link, publisher_rings
from ..processes import daemon_wire as dw
from ..registry.core import Core
from ..registry.follow import RegistryFollower

log = logging.getLogger("ln_manager")

RETRY_S = 2.0  # a refused or unreachable placement is tried again this often


@dataclass
class PullPlacement:
    """One pull topic on one host: what that host's daemon was (or is to be) told."""

    topic: str
    host: str
    ring: str
    md_name: str
    layout_hash: int
    message_size: int
    name: str  # the NDN URI
    setting: model.PullSetting
    error: str = ""  # the daemon's refusal, or why it cannot be reached
    adopted: bool = False  # found on the daemon, left by a previous manager

    def same(self, other: PullPlacement) -> bool:
        return not self.adopted and (
            self.ring, self.md_name, self.layout_hash, self.message_size, self.name,
            self.setting) == (other.ring, other.md_name, other.layout_hash,
                              other.message_size, other.name, other.setting)

    def info(self) -> dict[str, Any]:
        s = self.setting
        return {"topic": self.topic, "host": self.host, "name": self.name,
                "address": s.address, "port": s.port, "history": s.history,
                "freshness_ms": s.freshness_ms,
                "signature": "HMAC-SHA256" if s.key else "DigestSha256",
                "md_name": self.md_name, "error": self.error}


class PullTopics(RegistryFollower):
    """Every pull topic of the manager; `local_link` reaches the ln_daemon of the manager's
    own host (the daemons of other hosts come with their rings)."""

    def __init__(self, core: Core, config: model.Config, local_link: Link,
                 local_name: Callable[[], str]) -> None:
        super().__init__(core)
        self.config = config
        self.local_link = local_link
        self.local_name = local_name
        self.placements: dict[tuple[str, str], PullPlacement] = {}

    # ---- life -------------------------------------------------------------------------------
    def start(self) -> None:
        super().start()
        self._dirty.set()

    def configure(self, config: model.Config) -> None:
        """A reloaded configuration: topics it serves differently are placed again."""
        self.config = config
        self._dirty.set()

    async def adopt(self) -> None:
        """Note the pull topics a predecessor of this instance left in the local daemon, so
        that the first pass removes those no longer wanted (once their topic is not held
        for returning clients) and places the others again."""
        try:
            status = await (await self.local_link()).pull_status("")
        except (dw.DaemonError, OSError, TimeoutError) as exc:
            log.info("pull topics of a previous manager: cannot ask the local daemon: %s", exc)
            return
        host = self.local_name()
        for t in status.topics:
            setting = model.PullSetting("ndn-udp", t.port, None, t.history,
                                        address=t.address or "0.0.0.0")
            self.placements.setdefault((t.topic, host), PullPlacement(
                t.topic, host, t.ring, "", 0, 0, t.name, setting, adopted=True))

    async def close(self, remove: bool = True) -> None:
        """Stop following the registry; with `remove` also stop serving every pull topic of
        this instance on the daemons (a detaching manager leaves them served)."""
        await self._stop_following()
        if remove:
            async with self._lock:
                for host in sorted({p.host for p in self.placements.values()}):
                    await self._quietly(host, "")
                self.placements.clear()

    async def _follow(self) -> None:
        while True:
            # again after RETRY_S while a refusal waits, or an adopted topic is held
            retry = any(p.error or p.adopted for p in self.placements.values())
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._dirty.wait(), RETRY_S if retry else None)
            self._dirty.clear()
            await asyncio.sleep(0.05)  # one pass for a burst of changes
            try:
                await self.apply()
            except Exception:
                log.exception("placing pull topics failed")

    # ---- where topics live --------------------------------------------------------------------
    def desired(self) -> dict[tuple[str, str], tuple[PullPlacement, Any]]:
        """(topic, host) -> (placement, rings) for every pull topic with a publisher now."""
        out = {}
        instance = self.config.instance.name
        for topic in list(self.core.registry.topics.values()):
            setting = model.topic_pull(self.config, topic.name)
            if setting is None:
                continue
            for host, rings, ring in publisher_rings(self.core, self.local_name, topic):
                out[(topic.name, host)] = (PullPlacement(
                    topic.name, host, ring, topic.md_name, topic.layout_hash,
                    topic.message_size, pull_uri(setting, instance, topic.name), setting),
                    rings)
        return out

    async def apply(self) -> None:
        """Tell the daemons about every pull topic that has a publisher now (again where a
        daemon refused before), and remove those that lost theirs."""
        async with self._lock:
            want = self.desired()
            topics = self.core.registry.topics
            for key, old in list(self.placements.items()):
                held = getattr(topics.get(old.topic), "held", False)  # its clients may be back
                if key not in want and not held:
                    del self.placements[key]
                    await self._quietly(old.host, old.topic)
            for key, (new, rings) in want.items():
                old = self.placements.get(key)
                if old is not None and not old.error and old.same(new):
                    continue
                self.placements[key] = new
                await self._place(new, rings)

    async def _place(self, p: PullPlacement, rings: Any) -> None:
        s = p.setting
        try:
            link = await self._link(rings)
            await link.pull_topic(p.topic, p.ring, p.md_name, p.layout_hash, p.message_size,
                                  s.address, s.port, p.name, s.history, s.freshness_ms, s.key)
        except dw.DaemonError as exc:
            p.error = str(exc)
        except (OSError, TimeoutError, LookupError) as exc:
            p.error = f"the daemon cannot be reached: {exc}"
        if p.error:
            log.warning("pull topic %r on host %r: %s (trying again every %g s)", p.topic,
                        p.host, p.error, RETRY_S)
        else:
            log.info("pull topic %r served on host %r as %s, UDP port %d", p.topic, p.host,
                     p.name, s.port)

    async def _link(self, rings: Any) -> Any:
        if rings is self.core.local:
            return await self.local_link()
        link = getattr(rings, "link", None)
        if link is None:
            raise LookupError(f"host {rings.host!r} is unreachable: {rings.down_reason}")
        return link

    async def _host_link(self, host: str) -> Any:
        hosts = self.core.hosts
        if host == self.local_name() or hosts is None:
            return await self.local_link()
        rings = getattr(getattr(hosts, "hosts", {}).get(host), "rings", None)
        if rings is None:
            raise LookupError(f"unknown host {host!r}")
        return await self._link(rings)

    async def _quietly(self, host: str, topic: str) -> None:
        try:
            await (await self._host_link(host)).pull_remove(topic)
        except (dw.DaemonError, OSError, TimeoutError, LookupError) as exc:
            log.info("removing pull topic %r on host %r: %s", topic or "(all)", host, exc)

    # ---- views --------------------------------------------------------------------------------
    def listing(self) -> list[dict[str, Any]]:
        """The served pull topics, per host: NDN name, port, and a refusal if any."""
        return [p.info() for _, p in sorted(self.placements.items())]

    async def status(self) -> list[dict[str, Any]]:
        """Per host with pull topics: the producer's ports and topics with their counters;
        a topic the daemon refused shows the refusal."""
        out = []
        for host in sorted({p.host for p in self.placements.values()}):
            entry: dict[str, Any] = {"host": host, "error": "", "ports": [], "topics": []}
            try:
                status = await (await self._host_link(host)).pull_status("")
                entry["ports"] = [vars(p) for p in status.ports]
                mine = {p.topic: p.error for p in self.placements.values() if p.host == host}
                entry["topics"] = [{**vars(t), "error": mine.get(t.topic) or t.last_error}
                                   for t in status.topics]
            except (dw.DaemonError, OSError, TimeoutError, LookupError) as exc:
                entry["error"] = str(exc)
            served = {t["topic"] for t in entry["topics"]}
            for p in self.placements.values():
                if p.host == host and p.topic not in served:
                    info = p.info()
                    entry["topics"].append({**_ZERO, "topic": p.topic, "name": p.name,
                                            "ring": p.ring, "address": info["address"],
                                            "port": info["port"], "history": info["history"],
                                            "last_error": "", "error": p.error or
                                            "not served by the daemon"})
            out.append(entry)
        return out


_ZERO = dict.fromkeys(("latest_seq", "interests", "syncs", "data", "nacks", "parked",
                       "expired", "duplicates", "overflow"), 0)
