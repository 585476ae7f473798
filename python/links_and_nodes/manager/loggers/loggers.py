"""Topic loggers of a manager (docs/logging.md): named sets of topic patterns whose samples
the ln_daemon of each publisher's host keeps in a preallocated in-memory ring while the
logger is enabled.  This module decides where each logged topic lives (the ring of every
host with a publisher of it, following publishers and ring growth as the registry changes),
tells those daemons, and fetches and merges what they hold.  Topic data never passes
through here except on a download."""

from __future__ import annotations

import asyncio
import contextlib
import fnmatch
import logging
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any

from ... import logger_files
from ..config import model
from ..processes import daemon_wire as dw
from ..registry.core import Core
from ..registry.follow import RegistryFollower
from ..registry.model import PortKind, Topic, topic_name_problem

log = logging.getLogger("ln_manager")

MAX_DEPTH = 1 << 30
# A logged topic's ring gets at least this many slots (up to SLACK_BYTES of them, at least
# SLACK_MIN_SLOTS): how far the daemon's logger thread may fall behind the publisher before
# it misses a sample.  Publishers never wait for it either way.
SLACK_SLOTS = 64
SLACK_MIN_SLOTS = 8
SLACK_BYTES = 4 << 20
FETCH_BYTES = 4 << 20  # per daemon request while merging a download
NAME_CHARS = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.-")


class LoggerError(Exception):
    """A logger request that cannot be carried out; `code` is the LN_E* name it maps to."""

    def __init__(self, text: str, code: str = "EREFUSED") -> None:
        super().__init__(text)
        self.code = code


@dataclass(frozen=True)
class Pattern:
    """Topics a logger logs: a name or an fnmatch glob, with its ring geometry."""

    pattern: str
    depth: int
    divisor: int = 1
    span: float = 0.0

    def matches(self, topic: str) -> bool:
        return fnmatch.fnmatchcase(topic, self.pattern)

    def info(self) -> dict[str, Any]:
        return {"pattern": self.pattern, "depth": self.depth, "divisor": self.divisor,
                "span": self.span}


@dataclass
class Placement:
    """One topic of a logger on one host: what that host's daemon was told."""

    topic: str
    host: str
    ring: str
    md_name: str
    layout_hash: int
    message_size: int
    spec: Pattern
    active: bool = True  # False: no publisher there any more; its samples are still there
    error: str = ""


@dataclass
class Logger:
    name: str
    patterns: list[Pattern] = field(default_factory=list)
    enabled: bool = False
    placements: dict[tuple[str, str], Placement] = field(default_factory=dict)  # (topic, host)

    def spec_for(self, topic: str) -> Pattern | None:
        """The first pattern (in the order they were added) that matches `topic`."""
        return next((p for p in self.patterns if p.matches(topic)), None)


def check_name(name: Any) -> str:
    if not isinstance(name, str) or not name or not set(name) <= NAME_CHARS:
        raise LoggerError(f"bad logger name {name!r} (letters, digits, _ . -)", "EINVAL")
    return name


def check_pattern(pattern: Any, depth: Any, divisor: Any, span: Any) -> Pattern:
    if not isinstance(pattern, str) or not pattern:
        raise LoggerError("a logged topic needs a name or pattern", "EINVAL")
    if not any(c in pattern for c in "*?[") and (problem := topic_name_problem(pattern)):
        raise LoggerError(problem, "EINVAL")
    if isinstance(depth, bool) or not isinstance(depth, int) or not 1 <= depth <= MAX_DEPTH:
        raise LoggerError(f"depth must be an integer from 1 to {MAX_DEPTH}, got {depth!r}",
                          "EINVAL")
    if isinstance(divisor, bool) or not isinstance(divisor, int) or divisor < 1:
        raise LoggerError(f"divisor must be an integer >= 1, got {divisor!r}", "EINVAL")
    if isinstance(span, bool) or not isinstance(span, int | float) or not 0 <= span < 1e9:
        raise LoggerError(f"span must be seconds >= 0, got {span!r}", "EINVAL")
    return Pattern(pattern, depth, divisor, float(span))


def publisher_rings(core: Core, local_name: Callable[[], str],
                    topic: Topic) -> list[tuple[str, Any, str]]:
    """(host name, rings, segment name) of every host with a publisher of the topic."""
    out: dict[str, tuple[str, Any, str]] = {}
    hosts = core.hosts
    for port in topic.ports.values():
        if port.kind is not PortKind.PUBLISHER:
            continue
        try:
            rings = hosts.rings_for(port.client) if hosts is not None else core.local
        except Exception:  # a client on a host the manager does not know
            continue
        if not rings.has(topic.id):
            continue
        local = rings is core.local
        host = local_name() if local or hosts is None else rings.host
        out[host] = (host, rings, rings.current(topic.id))
    return list(out.values())


Link = Callable[[], Awaitable[Any]]  # the manager host's daemon client


class Loggers(RegistryFollower):
    """Every logger of the manager; `local_link` reaches the ln_daemon of the manager's own
    host (the daemons of other hosts come with their rings).  `_lock`: one change of the
    daemons' loggers at a time."""

    def __init__(self, core: Core, local_link: Link, local_name: Callable[[], str]) -> None:
        super().__init__(core)
        self.local_link = local_link
        self.local_name = local_name
        self.loggers: dict[str, Logger] = {}

    # ---- life -------------------------------------------------------------------------------
    async def close(self, remove: bool = True) -> None:
        """Stop following the registry; with `remove` also drop every logger from the
        daemons (a detaching manager leaves them, so that its successor finds the data)."""
        await self._stop_following()
        if remove:
            for name in list(self.loggers):
                with contextlib.suppress(LoggerError):
                    await self.remove(name)

    async def configure(self, config: model.Config) -> None:
        """The `logger` sections: their patterns added, autostart ones enabled.  A logger
        that cannot be set up is logged, never fatal (its status says why)."""
        for section in config.loggers.values():
            logger = self.loggers.setdefault(section.name, Logger(section.name))
            for t in section.topics:
                spec = Pattern(t.pattern, t.depth, t.divisor, t.span)
                if spec not in logger.patterns:
                    logger.patterns.append(spec)
            try:
                await self.apply(logger)
                if section.autostart and not logger.enabled:
                    await self.enable(section.name)
            except LoggerError as exc:
                log.warning("logger %r (%s): %s", section.name, section.location, exc)

    async def adopt(self) -> None:
        """Take over the loggers a predecessor of this instance left in the ln_daemon of the
        manager's host (it detached or died): their topics become patterns of the same
        name, their samples stay, and a logger enabled there stays enabled."""
        try:
            link = await self.local_link()
            status = await link.logger_status("")
            host = self.local_name()
            for t in status.topics:
                logger = self.loggers.setdefault(t.logger, Logger(t.logger))
                spec = logger.spec_for(t.topic)
                if spec is None:
                    spec = Pattern(t.topic, t.depth, t.divisor, t.span)
                    logger.patterns.append(spec)
                head = await link.logger_fetch(t.logger, t.topic, (1 << 64) - 1, 1)
                logger.placements[(t.topic, host)] = Placement(
                    t.topic, host, t.ring, t.md_name, head.layout_hash, t.message_size, spec,
                    active=False)
                logger.enabled = logger.enabled or t.enabled
                log.info("logger %r: took over topic %r (%d samples) from a previous manager",
                         t.logger, t.topic, t.stored)
        except (dw.DaemonError, OSError, TimeoutError) as exc:
            log.info("loggers of a previous manager: cannot ask the local daemon: %s", exc)

    async def _follow(self) -> None:
        """Re-place the loggers' topics whenever clients, ports or rings change."""
        while True:
            await self._dirty.wait()
            self._dirty.clear()
            await asyncio.sleep(0.05)  # one pass for a burst of changes
            for logger in list(self.loggers.values()):
                try:
                    await self.apply(logger)
                except LoggerError as exc:
                    log.warning("logger %r: %s", logger.name, exc)
                except Exception:
                    log.exception("logger %r: placing its topics failed", logger.name)

    # ---- where topics live --------------------------------------------------------------------
    def _rings_of(self, topic: Topic) -> list[tuple[str, Any, str]]:
        return publisher_rings(self.core, self.local_name, topic)

    async def _link(self, rings: Any) -> Any:
        if rings is self.core.local:
            return await self.local_link()
        link = getattr(rings, "link", None)
        if link is None:
            raise LoggerError(f"host {rings.host!r} is unreachable: {rings.down_reason}",
                              "ECONNECTION")
        return link

    async def _slack(self, logger: Logger) -> None:
        """Deepen the rings of the logger's topics (see SLACK_SLOTS)."""
        for topic in list(self.core.registry.topics.values()):
            if logger.spec_for(topic.name) is None or not topic.publishers:
                continue
            want = max(SLACK_MIN_SLOTS, min(SLACK_SLOTS, SLACK_BYTES // topic.message_size))
            if topic.slots < want:
                await self.core.ensure_slots(topic.name, want, f"logger {logger.name!r}")

    async def apply(self, logger: Logger) -> None:
        """Tell the daemons about every topic of `logger` that has a publisher now.  The
        first daemon refusal (e.g. its logger memory is exhausted) is raised after the
        others were tried; it is also kept in the placement's status."""
        await self._slack(logger)
        async with self._lock:
            failure: LoggerError | None = None
            seen: set[tuple[str, str]] = set()
            for topic in list(self.core.registry.topics.values()):
                spec = logger.spec_for(topic.name)
                if spec is None:
                    continue
                for host, rings, ring in self._rings_of(topic):
                    key = (topic.name, host)
                    seen.add(key)
                    old = logger.placements.get(key)
                    new = Placement(topic.name, host, ring, topic.md_name, topic.layout_hash,
                                    topic.message_size, spec)
                    if old is not None and old.active and not old.error and (
                            old.ring, old.spec, old.layout_hash, old.message_size) == (
                            ring, spec, topic.layout_hash, topic.message_size):
                        continue
                    logger.placements[key] = new
                    try:
                        await self._place(logger, new, rings)
                    except LoggerError as exc:
                        new.error = str(exc)
                        failure = failure or exc
            for key, placement in logger.placements.items():
                if key not in seen:
                    placement.active = False
            if failure is not None:
                raise failure

    async def _place(self, logger: Logger, p: Placement, rings: Any) -> None:
        link = await self._link(rings)
        try:
            await link.logger_topic(logger.name, p.topic, p.ring, p.md_name, p.layout_hash,
                                    p.message_size, p.spec.depth, p.spec.divisor,
                                    p.spec.span)
            if logger.enabled:
                await link.logger_enable(logger.name, True, False)
        except dw.DaemonError as exc:
            code = "ELIMIT" if "memory" in str(exc) else "EREFUSED"
            raise LoggerError(f"topic {p.topic!r} on host {p.host!r}: {exc}", code) from None
        except (OSError, TimeoutError) as exc:
            raise LoggerError(f"topic {p.topic!r} on host {p.host!r}: the daemon cannot be "
                              f"reached: {exc}", "ECONNECTION") from None
        log.info("logger %r: topic %r logged on host %r (%d samples, divisor %d)",
                 logger.name, p.topic, p.host, p.spec.depth, p.spec.divisor)

    # ---- requests ---------------------------------------------------------------------------
    def get(self, name: Any) -> Logger:
        logger = self.loggers.get(check_name(name))
        if logger is None:
            known = ", ".join(sorted(self.loggers)) or "none"
            raise LoggerError(f"no logger {name!r} (loggers: {known})", "ENOTFOUND")
        return logger

    def open(self, name: Any) -> Logger:
        return self.loggers.setdefault(check_name(name), Logger(name))

    async def add(self, name: Any, spec: Pattern) -> None:
        """Add (or change) a pattern; refused, and nothing changed, if a daemon refuses a
        topic that has a publisher now (e.g. over its memory limit)."""
        logger = self.open(name)
        before = list(logger.patterns)
        logger.patterns = [p for p in logger.patterns if p.pattern != spec.pattern] + [spec]
        try:
            await self.apply(logger)
        except LoggerError:
            logger.patterns = before
            await self._forget_unmatched(logger)
            with contextlib.suppress(LoggerError):
                await self.apply(logger)
            raise

    async def remove(self, name: Any, pattern: str = "") -> None:
        """Remove a pattern (its topics' samples are dropped), or the whole logger."""
        logger = self.get(name)
        if pattern:
            if all(p.pattern != pattern for p in logger.patterns):
                raise LoggerError(f"logger {logger.name!r} has no topic {pattern!r}",
                                  "ENOTFOUND")
            logger.patterns = [p for p in logger.patterns if p.pattern != pattern]
            await self._forget_unmatched(logger)
            return
        for host in {p.host for p in logger.placements.values()}:
            await self._quietly(host, lambda link: link.logger_remove(logger.name, ""))
        del self.loggers[logger.name]

    async def _forget_unmatched(self, logger: Logger) -> None:
        for key, placement in list(logger.placements.items()):
            if logger.spec_for(placement.topic) is None:
                del logger.placements[key]
                await self._quietly(placement.host, lambda link, t=placement.topic:
                                    link.logger_remove(logger.name, t))

    async def _host_link(self, host: str) -> Any:
        hosts = self.core.hosts
        if host == self.local_name() or hosts is None:
            return await self.local_link()
        state = getattr(hosts, "hosts", {}).get(host)
        rings = getattr(state, "rings", None)
        if rings is None:
            raise LoggerError(f"unknown host {host!r}", "ENOTFOUND")
        return await self._link(rings)

    async def _quietly(self, host: str, call: Callable[[Any], Awaitable[Any]]) -> None:
        try:
            await call(await self._host_link(host))
        except (LoggerError, dw.DaemonError, OSError, TimeoutError) as exc:
            log.info("logger clean-up on host %r: %s", host, exc)

    async def _each_host(self, logger: Logger,
                         call: Callable[[Any], Awaitable[Any]]) -> None:
        errors = []
        for host in sorted({p.host for p in logger.placements.values()}):
            try:
                await call(await self._host_link(host))
            except dw.DaemonError as exc:
                errors.append(f"host {host!r}: {exc}")
            except (OSError, TimeoutError) as exc:
                errors.append(f"host {host!r}: the daemon cannot be reached: {exc}")
            except LoggerError as exc:
                errors.append(str(exc))
        if errors:
            raise LoggerError(f"logger {logger.name!r}: " + "; ".join(errors), "ECONNECTION")

    async def enable(self, name: Any, keep: bool = False) -> None:
        """Start a capture on every host of the logger (clearing what it held unless
        `keep`); topics that get a publisher later join it."""
        logger = self.get(name)
        logger.enabled = True
        await self._each_host(logger, lambda link: link.logger_enable(logger.name, True,
                                                                      not keep))

    async def disable(self, name: Any) -> None:
        logger = self.get(name)
        logger.enabled = False
        await self._each_host(logger, lambda link: link.logger_enable(logger.name, False,
                                                                      False))

    async def status(self, name: Any) -> dict[str, Any]:
        """The logger's patterns and, per topic and host, the daemon's counters."""
        logger = self.get(name)
        topics = []
        per_host: dict[str, dict[str, Any]] = {}
        for host in sorted({p.host for p in logger.placements.values()}):
            try:
                status = await (await self._host_link(host)).logger_status(logger.name)
                per_host[host] = {t.topic: t for t in status.topics}
            except (LoggerError, dw.DaemonError, OSError, TimeoutError) as exc:
                per_host[host] = {"": str(exc)}
        for (topic, host), p in sorted(logger.placements.items()):
            entry: dict[str, Any] = {"topic": topic, "host": host, "md_name": p.md_name,
                                     "layout_hash": f"{p.layout_hash:016x}",
                                     "message_size": p.message_size, "depth": p.spec.depth,
                                     "divisor": p.spec.divisor, "span": p.spec.span,
                                     "publisher_here": p.active, "error": p.error}
            found = per_host.get(host, {})
            daemon = found.get(topic)
            if daemon is not None and not isinstance(daemon, str):
                entry.update(enabled=daemon.enabled, received=daemon.received,
                             stored=daemon.stored, missed=daemon.missed,
                             skipped=daemon.skipped, dropped=daemon.dropped)
                entry["error"] = entry["error"] or daemon.last_error
            elif "" in found:
                entry["error"] = entry["error"] or str(found[""])
            topics.append(entry)
        return {"name": logger.name, "enabled": logger.enabled,
                "patterns": [p.info() for p in logger.patterns], "topics": topics}

    def listing(self) -> list[dict[str, Any]]:
        return [{"name": lg.name, "enabled": lg.enabled, "patterns": len(lg.patterns),
                 "topics": len({p.topic for p in lg.placements.values()})}
                for lg in self.loggers.values()]

    async def fetch(self, name: Any, topic: str, host: str, after: int,
                    max_bytes: int) -> Any:
        """One chunk (daemon_client.LoggerChunk) of one topic on one host."""
        logger = self.get(name)
        if (topic, host) not in logger.placements:
            raise LoggerError(f"logger {logger.name!r} has no topic {topic!r} on host "
                              f"{host!r}", "ENOTFOUND")
        try:
            link = await self._host_link(host)
            return await link.logger_fetch(logger.name, topic, after, max_bytes)
        except dw.DaemonError as exc:
            raise LoggerError(f"logger {logger.name!r}, topic {topic!r} on host {host!r}: "
                              f"{exc}") from None
        except (OSError, TimeoutError) as exc:
            raise LoggerError(f"host {host!r}: the daemon cannot be reached: {exc}",
                              "ECONNECTION") from None

    async def download(self, name: Any) -> dict[str, dict[str, Any]]:
        """Every host's samples per topic, merged in publish-time order:
        topic -> {md_name, layout_hash, message_size, samples: [(seq, time_ns, bytes)],
        hosts, counters}."""
        logger = self.get(name)
        out: dict[str, dict[str, Any]] = {}
        for (topic, host), p in sorted(logger.placements.items()):
            entry = out.setdefault(topic, logger_files.new_entry(
                p.md_name, p.layout_hash, p.message_size, p.spec.divisor))
            samples: list[tuple[int, int, bytes]] = []
            after, until = 0, None
            while True:  # up to what the buffer held at the first chunk (it may be enabled)
                chunk = await self.fetch(logger.name, topic, host, after, FETCH_BYTES)
                until = chunk.last_seq if until is None else until
                samples.extend(s for s in chunk.samples if s[0] <= until)
                if not chunk.samples or chunk.samples[-1][0] >= until:
                    break
                after = chunk.samples[-1][0]
            logger_files.add_host(entry, host, samples, vars(chunk))
        for entry in out.values():
            entry["samples"].sort(key=lambda s: (s[1], s[0]))
        return out
