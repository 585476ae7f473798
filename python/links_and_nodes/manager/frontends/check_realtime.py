"""The real-time part of `ln_manager check`: a process that asks for SCHED_FIFO or SCHED_RR
with a priority this host will refuse (RLIMIT_RTPRIO below the priority and no
CAP_SYS_NICE) gets a warning at its `priority` (else `policy`) key.  Only processes on the
host where the check runs (the manager's) are checked, with the limits and capabilities of
the checking process, which a local ln_daemon started by the manager inherits; other hosts
are not checked."""

from __future__ import annotations

import resource
import socket
from dataclasses import dataclass
from pathlib import Path

from ..config.errors import Problem
from ..config.model import Config, Policy

CAP_SYS_NICE = 23  # linux/capability.h


@dataclass(frozen=True)
class HostLimits:
    """What the kernel will let this user's processes do: RLIMIT_RTPRIO's soft limit (None:
    unlimited) and whether CAP_SYS_NICE is effective (None: unknown)."""

    rtprio: int | None
    cap_sys_nice: bool | None

    def allows(self, priority: int) -> bool:
        if self.cap_sys_nice:
            return True
        return self.rtprio is None or priority <= self.rtprio


def cap_effective(status: str, cap: int) -> bool | None:
    """Whether bit `cap` is set in the CapEff line of a /proc/PID/status text."""
    for line in status.splitlines():
        if line.startswith("CapEff:"):
            try:
                return bool(int(line.split(":", 1)[1].strip(), 16) >> cap & 1)
            except ValueError:
                return None
    return None


def host_limits() -> HostLimits:
    """The limits of this process (the check runs where the manager runs)."""
    soft, _ = resource.getrlimit(resource.RLIMIT_RTPRIO)
    try:
        cap = cap_effective(Path("/proc/self/status").read_text(), CAP_SYS_NICE)
    except OSError:
        cap = None
    return HostLimits(None if soft == resource.RLIM_INFINITY else soft, cap)


def realtime_warnings(config: Config, local_host: str | None = None,
                      limits: HostLimits | None = None) -> list[Problem]:
    """A warning for every process on this host whose real-time policy cannot be applied."""
    from ..network.routes import host_of

    local_host = local_host or socket.gethostname()
    limits = limits or host_limits()
    found = []
    for p in config.processes.values():
        if p.policy is Policy.OTHER or limits.allows(p.priority):
            continue
        if host_of(config, p.node, local_host) != local_host:
            continue  # another host: its limits are not known here
        loc = p.key_locations.get("priority") or p.key_locations.get("policy") or p.location
        limit = "unlimited" if limits.rtprio is None else str(limits.rtprio)
        found.append(Problem(loc, (
            f"process '{p.name}': {p.policy.value} with priority {p.priority} cannot be applied "
            f"on this host: RLIMIT_RTPRIO is {limit} (below {p.priority}) and CAP_SYS_NICE is "
            "not effective, so its start would fail (raise 'rtprio' in "
            "/etc/security/limits.conf or `ulimit -r`, or give the daemon CAP_SYS_NICE; "
            "docs/realtime.md)")))
    return found
