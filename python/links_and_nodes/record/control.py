"""The wait of ln_play's loop: while it waits for the next sample's time it answers the
control service, applies keyboard commands and publishes the replay clock, all on the
player's own thread, so no command ever races with a publish."""

from __future__ import annotations

import contextlib
import queue
import time
from collections.abc import Callable
from typing import Any

from .control_service import CONTROL_GROUP
from .playback import CommandError, Playback, Quit

KEY_POLL_S = 0.02  # keys are looked at least this often
STATUS_LINE_S = 0.2


class Controller:
    """Controller(...).wait is the `wait` of Playback.run."""

    def __init__(self, playback: Playback, client: Any = None,
                 keys: queue.Queue[tuple[Any, ...]] | None = None, clock: Any = None,
                 status_line: Callable[[Any], None] | None = None) -> None:
        self.playback, self.client, self.keys = playback, client, keys
        self.clock, self.status_line = clock, status_line
        self._status_due = 0.0
        if clock is not None:
            playback.on_change.append(clock.publish)
        if status_line is not None:
            playback.on_change.append(lambda pb: status_line(pb.status()))

    def wait(self, timeout: float) -> None:
        """Wait up to `timeout` seconds (0: only look once); return early once a command has
        changed something."""
        deadline = time.monotonic() + timeout
        epoch = self.playback.epoch
        while True:
            if self._periodic() or self.playback.epoch != epoch:
                return
            left = max(0.0, deadline - time.monotonic())
            if self.clock is not None:
                left = min(left, self.clock.tick(self.playback))
            if self.keys is not None:
                left = min(left, KEY_POLL_S)
            if self.client is not None:
                self.client.wait_and_handle_service_group_requests(CONTROL_GROUP, left)
            elif left > 0:
                time.sleep(left)
            if self.playback.epoch != epoch or time.monotonic() >= deadline:
                return

    def _periodic(self) -> bool:
        """Keys, the clock and the status line; True if a key changed something."""
        changed = False
        if self.keys is not None:
            while True:
                try:
                    cmd = self.keys.get_nowait()
                except queue.Empty:
                    break
                self._key(cmd)
                changed = True
        if self.clock is not None:
            self.clock.tick(self.playback)
        now = time.monotonic()
        if self.status_line is not None and now >= self._status_due:
            self._status_due = now + STATUS_LINE_S
            self.status_line(self.playback.status())
        return changed

    def _key(self, cmd: tuple[Any, ...]) -> None:
        pb = self.playback
        if cmd[0] == "quit":
            raise Quit
        if cmd[0] == "toggle":
            pb.resume() if pb.paused else pb.pause()
        elif cmd[0] == "step":
            pb.step()
        elif cmd[0] == "seek_by":
            pb.seek(pb.position() + cmd[1])
        elif cmd[0] == "rate_by":
            with contextlib.suppress(CommandError):  # a rate that overflowed: keep the old
                pb.set_rate(pb.rate * cmd[1])
