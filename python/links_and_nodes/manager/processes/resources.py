"""The newest resource sample of every host and process (EV_RESOURCES of the daemons,
docs/process_management.md "Resources and limits"), and the `.lnc` limits `max_rss` and
`max_cpu` checked against them.  The scheduler feeds it and acts on a limit exceeded
(managed.py); the commands read it (frontends/commands/resource_view.py)."""

from __future__ import annotations

from typing import Any

from ...tools.commands.columns import size_text
from ..config import model
from .daemon_resources import HostSample, ProcessSample, ResourceSample

# The scheme of resource signals (docs/webui.md, "Resources"): "host/<host>/<figure>" and
# "process/<name>/<figure>", the figures below.
HOST_SIGNALS = ("cpu", "load1", "mem_used", "mem_available")
PROCESS_SIGNALS = ("cpu", "rss", "threads", "fds")


def limit_problem(cfg: model.Process, sample: ProcessSample) -> str:
    """Why `sample` is over the process's limits, or ""."""
    problems = []
    if cfg.max_rss is not None and sample.rss > cfg.max_rss:
        problems.append(f"RSS {size_text(sample.rss)} > max_rss {size_text(cfg.max_rss)}")
    if cfg.max_cpu is not None and sample.cpu is not None and sample.cpu > cfg.max_cpu:
        problems.append(f"CPU {sample.cpu:.0f} % > max_cpu {cfg.max_cpu:g} %")
    return "; ".join(problems)


class Resources:
    """The newest samples: hosts by host name, processes by process name."""

    def __init__(self) -> None:
        self.hosts: dict[str, HostSample] = {}
        self.processes: dict[str, ProcessSample] = {}
        self._source_of: dict[str, int] = {}  # process name -> daemon of its sample

    def take(self, sample: ResourceSample, source: int) -> None:
        """The newest sample of the daemon (connection) `source`: its processes replace the
        ones it sampled before."""
        self.hosts[sample.host.host] = sample.host
        for name in [n for n, s in self._source_of.items() if s == source]:
            del self._source_of[name]
            self.processes.pop(name, None)  # not running there any more
        for p in sample.processes:
            self.processes[p.name] = p
            self._source_of[p.name] = source

    def process(self, name: str, pid: int | None) -> ProcessSample | None:
        """The newest sample of process `name` while it runs as `pid`."""
        p = self.processes.get(name)
        return p if p is not None and pid is not None and p.pid == pid else None

    def host_listing(self) -> list[dict[str, Any]]:
        return [h.as_dict() for _, h in sorted(self.hosts.items())]

    def process_fields(self, name: str, pid: int | None) -> dict[str, Any]:
        """The resource columns of a process row: None where there is no sample."""
        p = self.process(name, pid)
        if p is None:
            return {"cpu": None, "rss": None, "threads": None, "fds": None,
                    "ctx_voluntary": None, "ctx_involuntary": None}
        return {"cpu": p.cpu, "rss": p.rss, "threads": p.threads, "fds": p.fds,
                "ctx_voluntary": p.voluntary, "ctx_involuntary": p.involuntary}

    def signals(self) -> dict[str, float]:
        """Every resource signal with its newest value (the scheme above)."""
        out: dict[str, float] = {}
        for name, h in self.hosts.items():
            host = {"cpu": h.cpu, "load1": h.load[0], "mem_used": h.mem_total - h.mem_available,
                    "mem_available": h.mem_available}
            for figure in HOST_SIGNALS:
                out[f"host/{name}/{figure}"] = float(host[figure])
        for name, p in self.processes.items():
            for figure in PROCESS_SIGNALS:
                value = getattr(p, figure)
                if value is not None:
                    out[f"process/{name}/{figure}"] = float(value)
        return out
