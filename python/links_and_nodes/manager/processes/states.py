"""The state machine of a managed process (docs/process_management.md, "States").  A leaf
module: the states, which transitions are allowed, and which states count as running.

    stopped ──start──► starting ──spawned──► started ──ready──► ready
       ▲                  │                     │                 │
       │             spawn failed          exit / stop       exit / stop
       │                  ▼                     ▼                 ▼
       ├──────────── failed ◄──── exit≠0 ── stopping ◄── stop ────┘
       │                                        │
       └────────────── finished ◄── exit 0 ─────┘ (or a stop that was asked for: stopped)

`finished`: it exited by itself with status 0 (with the flag `no_error_on_stop`: with
any status); `failed`: it could not start, exited with a non-zero status or a signal it was
not sent, or gave up restarting.  A restart goes failed/finished → starting.
"""

from __future__ import annotations

import enum


class ProcState(enum.Enum):
    STOPPED = "stopped"
    STARTING = "starting"
    STARTED = "started"
    READY = "ready"
    STOPPING = "stopping"
    FINISHED = "finished"
    FAILED = "failed"


S = ProcState

# Every allowed (from, to); anything else is a bug and raises.
TRANSITIONS: frozenset[tuple[ProcState, ProcState]] = frozenset({
    (S.STOPPED, S.STARTING), (S.FINISHED, S.STARTING), (S.FAILED, S.STARTING),
    (S.STARTING, S.STARTED), (S.STARTING, S.READY), (S.STARTING, S.FAILED),
    (S.STARTING, S.STOPPED),  # stop asked for while a dependency was still starting
    (S.STARTED, S.READY), (S.STARTED, S.STOPPING), (S.STARTED, S.FINISHED),
    (S.STARTED, S.FAILED),
    (S.READY, S.STOPPING), (S.READY, S.FINISHED), (S.READY, S.FAILED),
    (S.STOPPING, S.STOPPED), (S.STOPPING, S.FINISHED), (S.STOPPING, S.FAILED),
    # a process found running by a new manager (re-attach)
    (S.STOPPED, S.STARTED), (S.STOPPED, S.READY),
    # an exited process found by a new manager
    (S.STOPPED, S.FINISHED), (S.STOPPED, S.FAILED),
})

# States in which the OS process exists.
ALIVE = frozenset({S.STARTED, S.READY, S.STOPPING})
# States from which `start` does something.
STARTABLE = frozenset({S.STOPPED, S.FINISHED, S.FAILED})


def check_transition(old: ProcState, new: ProcState) -> None:
    if (old, new) not in TRANSITIONS:
        raise ValueError(f"illegal process state transition {old.value} -> {new.value}")
