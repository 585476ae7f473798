"""The replay of a checked recording: a timeline (playing or paused, rate, position) that
publishes each sample when its time comes, and the commands that change it (pause, resume,
step, seek, set_rate).  Commands run on the one thread that publishes, between two samples
(from the `wait` function it is given), so they never race with a publish.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass

from .player import Publisher, Recording, Stored, decode_stored, in_time_order, stored_samples

MAX_WAIT_S = 0.1  # the loop looks at its state at least this often
LOOK_S = 0.02  # and calls wait() at least this often, also when it has no time to wait
COMMANDS = ("pause", "resume", "step", "seek", "set_rate", "status")


class CommandError(ValueError):
    """A control command that cannot be done; the text says why."""


class Quit(Exception):
    """Ends the replay on request (the keyboard's q)."""


@dataclass(frozen=True)
class Status:
    """What a control command answers."""

    state: str  # playing | paused | finished
    position_ns: int  # replay time now (paused: where it stands)
    rate: float
    played: int  # samples published so far
    first_ns: int  # the recording's first and last sample (0: none)
    last_ns: int
    epoch: int  # +1 on every change of the timeline (the clock's epoch)


Waiter = Callable[[float], None]  # waits up to that many seconds, applying commands


class Playback:
    """Publishes the samples of the topics in `ports` with their recorded timing divided by
    `rate`, from `start_ns` (replay time) on; again and again with `loop`.  At the end it
    returns, unless `hold`: then it stays (state finished) until a seek or Quit."""

    def __init__(self, rec: Recording, ports: dict[str, Publisher], rate: float = 1.0,
                 start_ns: int | None = None, loop: bool = False, paused: bool = False,
                 hold: bool = False) -> None:
        self.rec, self.ports = rec, ports
        self.rate, self.loop, self.paused, self.hold = rate, loop, paused, hold
        self.played = 0
        self.epoch = 0
        self.on_change: list[Callable[[Playback], None]] = []  # after every command
        self.on_sample: list[Callable[[int], None]] = []  # after every publish
        self._wanted = list(ports)
        self._any = any(rec.counts.get(t, 0) for t in ports)
        self._start_ns = start_ns if start_ns is not None else (rec.first_ns or 0)
        self._iter: Iterator[tuple[int, Stored]] = iter(())
        self._next: tuple[int, Stored] | None = None
        # (replay time, monotonic time then, rate): one tuple, so that another thread (the
        # service call replay) reading position() never sees half of a change
        self._line = (self._start_ns, time.monotonic(), rate)
        self._open(self._start_ns)
        if self._next is not None:
            self._set_anchor(self._next[0])

    # ---- the timeline --------------------------------------------------------------------
    def position(self, now: float | None = None) -> int:
        """The replay time at monotonic time `now` (default: now)."""
        if self.paused or self._next is None:
            return self._line[0]
        anchor_t, anchor_wall, rate = self._line
        now = time.monotonic() if now is None else now
        return anchor_t + int((now - anchor_wall) * rate * 1e9)

    @property
    def state(self) -> str:
        return "finished" if self._next is None else "paused" if self.paused else "playing"

    def status(self) -> Status:
        return Status(self.state, self.position(), self.rate, self.played,
                      self.rec.first_ns or 0, self.rec.last_ns or 0, self.epoch)

    def _open(self, from_ns: int) -> None:
        """Read the files again from the start, skipping samples before `from_ns` (in the
        order of in_time_order, so the reordering window works as without a seek)."""
        ordered = in_time_order(stored_samples(self.rec, self._wanted))
        self._iter = ((t, s) for t, s in ordered if t >= from_ns)
        self._next = next(self._iter, None)

    def _reanchor(self, t_ns: int) -> None:
        self._line = (t_ns, time.monotonic(), self.rate)

    def _set_anchor(self, t_ns: int) -> None:
        """The replay time (where a pause stands), keeping the rest of the line."""
        self._line = (t_ns, *self._line[1:])

    def _changed(self) -> None:
        self.epoch += 1
        for fn in self.on_change:
            fn(self)

    # ---- commands ------------------------------------------------------------------------
    def pause(self) -> None:
        if self.paused:
            return
        pos = self.position()
        if self._next is not None:
            pos = min(pos, self._next[0])  # never ahead of what was published
        self._reanchor(pos)  # then paused: a reader in between sees no jump
        self.paused = True
        self._changed()

    def resume(self) -> None:
        if not self.paused:
            return
        self.paused = False
        self._reanchor(self._line[0])
        self._changed()

    def step(self) -> None:
        """Publish the next sample, exactly one (pausing first when playing)."""
        if not self.paused:
            self.pause()
        if self._next is not None:
            self._set_anchor(self._next[0])
            self._publish_next()
        self._changed()

    def seek(self, t_ns: int) -> None:
        """Go to replay time `t_ns`: the next sample is the first one at or after it."""
        self._open(t_ns)
        self._reanchor(t_ns)
        self._changed()

    def set_rate(self, rate: float) -> None:
        if not (rate > 0 and math.isfinite(rate)):
            raise CommandError(f"set_rate: the rate must be a positive number, not {rate}")
        self._line = (self.position(), time.monotonic(), rate)
        self.rate = rate
        self._changed()

    def command(self, name: str, time_ns: int = 0, relative: bool = False,
                rate: float = 0.0) -> Status:
        """One command of the control service (md ln/player): its status afterwards;
        CommandError for an unknown one or bad arguments."""
        if name == "pause":
            self.pause()
        elif name == "resume":
            self.resume()
        elif name == "step":
            self.step()
        elif name == "seek":
            self.seek((self.rec.first_ns or 0) + time_ns if relative else time_ns)
        elif name == "set_rate":
            self.set_rate(rate)
        elif name != "status":
            raise CommandError(f"unknown command {name!r}: one of {', '.join(COMMANDS)}")
        return self.status()

    # ---- the loop ------------------------------------------------------------------------
    def _publish_next(self) -> None:
        assert self._next is not None
        sample = decode_stored(self.rec, self._next[1])
        self.ports[sample.topic].write(sample.data)
        self.played += 1
        self._next = next(self._iter, None)
        for fn in self.on_sample:
            fn(self.played)
        if self._next is None:  # the end: the time stands still from here
            self._set_anchor(max(self._line[0], self.position()))
            self._changed()

    def _at_end(self, wait: Waiter) -> bool:
        """The end of the samples: True to return from run()."""
        if self.loop and self._any:
            self._open(self.rec.first_ns or 0)
            if self._next is not None:
                self._reanchor(self._next[0])
            self._changed()
            return False
        if not self.hold:
            return True
        wait(MAX_WAIT_S)
        return False

    def run(self, wait: Waiter | None = None) -> int:
        """Play until the end (or Quit / KeyboardInterrupt from `wait`, which waits up to the
        seconds it is given and may run commands meanwhile); returns the samples published."""
        wait = wait or time.sleep
        self._reanchor(self._line[0])
        looked = time.monotonic()
        while True:
            if self._next is None:
                if self._at_end(wait):
                    return self.played
                continue
            if self.paused:
                wait(MAX_WAIT_S)
                continue
            now = time.monotonic()
            anchor_t, anchor_wall, rate = self._line
            delay = anchor_wall + (self._next[0] - anchor_t) / 1e9 / rate - now
            if delay > 0 or now - looked > LOOK_S:  # a player behind still takes commands
                wait(min(max(delay, 0.0), MAX_WAIT_S))
                # from the end of the wait: one that took longer than LOOK_S (a loaded
                # machine) must not make the next turn wait again instead of publishing
                looked = time.monotonic()
                continue
            self._publish_next()
