"""The configuration's states (`state` sections): a check command says whether one is UP,
an up command brings it up.  Processes that depend on a state wait for it; the commands run
as short-lived processes of the node's daemon."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field

from ..config import model
from .backend import Backend, DaemonLink, StartError
from .daemon_wire import Exited
from .spawning import base_environment

log = logging.getLogger("ln_manager")


@dataclass
class StateRuntime:
    cfg: model.State
    up: bool | None = None
    checked_at: float = 0.0
    lock: asyncio.Lock = field(default_factory=asyncio.Lock)


class StateCommands:
    """The states of the configuration and the commands that check them and bring them up.
    `link(node)` is the scheduler's daemon connection of a node, whose exit events come
    back through `exited`."""

    def __init__(self, config: model.Config, backend: Backend,
                 link: Callable[[str], Awaitable[DaemonLink]],
                 manager_address_for: Callable[[str], str]) -> None:
        self.states = {name: StateRuntime(cfg) for name, cfg in config.states.items()}
        self._backend = backend
        self._link = link
        self._manager_address_for = manager_address_for
        self._count = 0
        # running commands: their exit, and the daemon connection they use
        self._waiters: dict[str, tuple[asyncio.Future[Exited], DaemonLink]] = {}

    def configure(self, config: model.Config) -> None:
        """Take a reloaded configuration: changed states are checked again."""
        self.states = {name: (self.states[name] if name in self.states
                              and self.states[name].cfg == st else StateRuntime(st))
                       for name, st in config.states.items()}

    def exited(self, event: Exited) -> bool:
        """Take the exit event of one of the commands; False if it is none of them."""
        waiter, _ = self._waiters.get(event.name, (None, None))
        if waiter is None or waiter.done():
            return False
        waiter.set_result(event)
        return True

    def daemon_lost(self, link: DaemonLink, node: str) -> None:
        """The commands running through `link` fail."""
        for future, used in self._waiters.values():
            if used is link and not future.done():
                future.set_exception(StartError(f"lost the ln_daemon of node {node!r}"))

    async def up(self, name: str, node: str) -> None:
        """Until state `name` is UP (checked at most every min_check_interval), its up
        command run if it is not; StartError if it stays DOWN."""
        st = self.states[name]
        node = st.cfg.node or node
        async with st.lock:
            fresh = time.monotonic() - st.checked_at < st.cfg.min_check_interval
            if st.up and fresh:
                return
            if await self._check(st, node):
                return
            if st.cfg.up is None:
                raise StartError(f"state {name} is DOWN (check failed) and has no up command")
            code = await self._run(node, f"{name}.up", st.cfg.up)
            if code != 0 or not await self._check(st, node):
                raise StartError(f"state {name} stays DOWN after its up command "
                                 f"(exit status {code})")

    async def _check(self, st: StateRuntime, node: str) -> bool:
        code = await self._run(node, f"{st.cfg.name}.check", st.cfg.check)
        st.up = code == 0
        st.checked_at = time.monotonic()
        log.info("state %s: %s", st.cfg.name, "UP" if st.up else "DOWN")
        return st.up

    async def _run(self, node: str, label: str, command: str) -> int | None:
        """Run a shell command on `node` through its daemon; its exit status (None if it
        died by a signal)."""
        self._count += 1
        name = f"state:{label}:{self._count}"
        try:
            link = await self._link(node)
        except (OSError, self._backend.error_type) as exc:
            raise StartError(f"{label}: {exc}") from None
        future: asyncio.Future[Exited] = asyncio.get_running_loop().create_future()
        self._waiters[name] = (future, link)
        env = base_environment(self._manager_address_for(node))
        spec = self._backend.spawn_spec(name=name, command=command, shell=True, env=env,
                                        use_pty=False, max_output_lines=100)
        try:
            await link.spawn(spec)
            exited = await future
        except self._backend.error_type as exc:
            raise StartError(f"{label}: cannot run {command!r}: {exc}") from None
        finally:
            self._waiters.pop(name, None)
        with contextlib.suppress(self._backend.error_type):
            await link.forget(name)
        return exited.exit_code
