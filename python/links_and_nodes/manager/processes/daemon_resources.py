"""Resource samples of a daemon's host and of the instance's processes on it (the EV_RESOURCES
event, docs/daemon.md "Resource samples"), as the manager holds them; decoded from the payload
by the schema-driven codec of daemon_wire.  No I/O here."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

from .daemon_wire import decode


@dataclass(frozen=True)
class ProcessSample:
    name: str
    pid: int
    cpu: float | None  # % of one core since the previous sample; None at the first
    rss: int  # bytes
    threads: int
    voluntary: int  # context switches since the start
    involuntary: int
    fds: int  # open file descriptors


@dataclass(frozen=True)
class NetRate:
    interface: str
    rx: float  # bytes/s
    tx: float


@dataclass(frozen=True)
class HostSample:
    host: str  # the daemon's host name
    time: float  # time.time() of the sample
    load: tuple[float, float, float]  # 1, 5 and 15 minutes
    cpu: float  # % busy of all CPUs together
    cpus: list[float]  # % busy per CPU
    mem_total: int  # bytes
    mem_available: int
    swap_total: int
    swap_free: int
    nets: list[NetRate] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["load"] = list(self.load)
        return d


@dataclass(frozen=True)
class ResourceSample:
    """One EV_RESOURCES: the host and the instance's running processes on it."""

    host: HostSample
    processes: list[ProcessSample]


def decode_resources(payload: bytes) -> ResourceSample:
    """An EV_RESOURCES payload; WireError if it is malformed."""
    f = decode("EV_RESOURCES", payload)
    host = HostSample(
        host=f["host"], time=f["time"], load=(f["load1"], f["load5"], f["load15"]),
        cpu=f["cpu"], cpus=list(f["cpus"]), mem_total=f["mem_total"],
        mem_available=f["mem_available"], swap_total=f["swap_total"],
        swap_free=f["swap_free"],
        nets=[NetRate(n["interface"], n["rx"], n["tx"]) for n in f["nets"]])
    procs = [ProcessSample(p["name"], p["pid"], p["cpu"] if p["cpu"] >= 0 else None, p["rss"],
                           p["threads"], p["voluntary"], p["involuntary"], p["fds"])
             for p in f["processes"]]
    return ResourceSample(host, procs)
