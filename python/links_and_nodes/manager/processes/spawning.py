"""Turning a configured process into a SPAWN request: its fields (`spawn_fields`), its
environment (`environment`), and the per-host start rate limit (`RateLimiter`)."""

from __future__ import annotations

import asyncio
import dataclasses
import os
import time
from collections.abc import Callable
from typing import Any

from ..config import model
from .daemon_wire import SpawnSpec

BASE_ENV = ("PATH", "HOME", "USER", "LOGNAME", "LANG", "LC_ALL", "TZ", "TERM")
X11_ENV = ("DISPLAY", "XAUTHORITY")  # passed with the flag forward_x11


def spawn_fields(cfg: model.Process, env: list[str]) -> dict[str, Any]:
    """The SpawnSpec of a configured process, as keywords.  The fields whose shape differs
    between the configuration and the wire are converted here; every other field of
    SpawnSpec (a SPAWN field of wire/daemon.schema) is taken from the process's attribute of
    the same name, so a key the daemon applies needs no line here."""
    shaped: dict[str, Any] = dict(
        name=cfg.name, command=cfg.command, shell="start_in_shell" in cfg.flags,
        argv=cfg.argv or None, env=env, cwd=cfg.change_directory,
        rlimits=[(r.name, r.soft, r.hard) for r in cfg.resource_limits],
        policy=cfg.policy.value, use_pty="no_pty" not in cfg.flags,
        output_log=((cfg.output_log.path, cfg.output_log.size_limit,
                     cfg.output_log.keep_count) if cfg.output_log else None))
    for f in dataclasses.fields(SpawnSpec):
        if f.name not in shaped and hasattr(cfg, f.name):
            shaped[f.name] = getattr(cfg, f.name)
    return shaped


def base_environment(manager_address: str) -> dict[str, str]:
    """What every command the scheduler runs gets: the manager's basic variables and where
    the manager is."""
    env = {k: os.environ[k] for k in BASE_ENV if k in os.environ}
    env["LN_MANAGER"] = manager_address
    return env


def environment(cfg: model.Process, config: model.Config, manager_address: str,
                extra_env: dict[str, str]) -> dict[str, str]:
    """The environment of a configured process on its node (`manager_address`: the
    manager as that node reaches it)."""
    env = {k: os.environ[k] for k in BASE_ENV if k in os.environ}
    env.update({k: os.environ[k] for k in cfg.pass_environment if k in os.environ})
    if "forward_x11" in cfg.flags:  # the manager's X display
        env.update({k: os.environ[k] for k in X11_ENV if k in os.environ})
    env["LN_MANAGER"] = manager_address
    env["LN_PROGRAM_NAME"] = cfg.name.replace("/", ".")
    if cfg.parameters:  # initial overrides of its parameter blocks (docs/parameters.md)
        from ...tools.parameters.values import to_json

        env["LN_PARAMETERS"] = to_json(cfg.parameters)
    dirs = cfg.message_definition_dirs + config.message_definition_dirs
    if dirs:
        env["LN_MESSAGE_DEFINITION_DIRS"] = ":".join(dirs)
    env.update(extra_env)
    env.update(cfg.environment)
    return env


class RateLimiter:
    """At most `rate` starts per second on one host (None: no limit)."""

    def __init__(self, rate: float | None) -> None:
        self.interval = 1.0 / rate if rate else 0.0
        self._next = 0.0
        self._lock = asyncio.Lock()

    async def acquire(self) -> None:
        if not self.interval:
            return
        async with self._lock:
            now = time.monotonic()
            if self._next > now:
                await asyncio.sleep(self._next - now)
            self._next = max(now, self._next) + self.interval


class RateLimiters:
    """One RateLimiter per host, by the hosts' `process_start_rate_limit`."""

    def __init__(self, config: Callable[[], model.Config]) -> None:
        self._config = config
        self._limiters: dict[str, RateLimiter] = {}

    def for_node(self, node: str) -> RateLimiter:
        config = self._config()
        host = config.node_map.get(node, node)
        if host not in self._limiters:
            h = config.hosts.get(host)
            self._limiters[host] = RateLimiter(h.process_start_rate_limit if h else None)
        return self._limiters[host]

    def clear(self) -> None:
        """Forget the limits (a reload may have changed them)."""
        self._limiters.clear()
