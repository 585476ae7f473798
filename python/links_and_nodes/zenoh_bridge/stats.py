"""The counters of ln_zenoh, per bridged topic and service, and how they are shown: a table on
stderr (SIGUSR1, every --stats-interval seconds, at exit) and a JSON file (--stats-file)."""

from __future__ import annotations

import json
import os
import threading
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any


@dataclass
class TopicStats:
    """One topic.  Out: `read` from the ring, `sent` to Zenoh, `unmatched` read while no remote
    subscriber matched (not sent), `rate_limited`, `overruns` (ring overruns while reading).
    In: `received` from Zenoh, `published` here, `bad_attachment`, `bad_size`, `refused`
    (layout mismatch), `md_unavailable` (its md could not be had), `superseded` (a newer
    sample replaced it in the queue, or a queued topic's queue was full), `gaps` (sequence
    numbers missing between received samples), `forced` (queued: written although a subscriber
    here had no free buffer for HOLD_S, which lost its oldest sample: inbound.py).  Batches
    between bridges (native core): out `batches` put, in `batches` received and `bad_batches`
    (malformed, dropped whole)."""

    direction: str
    md_name: str = ""
    state: str = "starting"
    read: int = 0
    sent: int = 0
    unmatched: int = 0
    rate_limited: int = 0
    overruns: int = 0
    received: int = 0
    published: int = 0
    bad_attachment: int = 0
    bad_size: int = 0
    refused: int = 0
    md_unavailable: int = 0
    superseded: int = 0
    gaps: int = 0
    bytes: int = 0
    errors: int = 0
    last_seq: int = 0
    forced: int = 0
    batches: int = 0
    bad_batches: int = 0


@dataclass
class ServiceStats:
    direction: str
    md_name: str = ""
    state: str = "starting"
    calls: int = 0
    errors: int = 0
    bad_requests: int = 0


@dataclass
class Stats:
    topics: dict[str, TopicStats] = field(default_factory=dict)
    services: dict[str, ServiceStats] = field(default_factory=dict)
    unknown_keys: int = 0  # samples of topics past an inbound rule's limit of 1024 names
    # malformed batches of topics not set up yet, per inbound rule (native.InRule.bad_batches)
    stray_batches: list[Any] = field(default_factory=list, repr=False, compare=False)
    lock: threading.Lock = field(default_factory=threading.Lock, repr=False, compare=False)
    # counters the native core adds to (native.Counters), per topic key; shown summed with
    # the topic's own (last_seq: the core's once it has one)
    native: dict[str, list[Any]] = field(default_factory=dict, repr=False, compare=False)

    def topic(self, name: str, direction: str) -> TopicStats:
        key = f"{direction}:{name}"
        with self.lock:
            stats = self.topics.get(key)
            if stats is None:
                stats = self.topics[key] = TopicStats(direction)
            return stats

    def add_native(self, name: str, direction: str, counters: Any) -> None:
        """Count what the native core counts in `counters` as the topic's too."""
        with self.lock:
            self.native.setdefault(f"{direction}:{name}", []).append(counters)

    def service(self, name: str, direction: str) -> ServiceStats:
        key = f"{direction}:{name}"
        with self.lock:
            stats = self.services.get(key)
            if stats is None:
                stats = self.services[key] = ServiceStats(direction)
            return stats

    def as_dict(self) -> dict[str, Any]:
        with self.lock:
            return {"topics": {k: self._merged(k, asdict(v)) for k, v in self.topics.items()},
                    "services": {k: asdict(v) for k, v in self.services.items()},
                    "unknown_keys": self.unknown_keys,
                    "bad_batches": sum(count() for count in self.stray_batches)}

    def _merged(self, key: str, topic: dict[str, Any]) -> dict[str, Any]:
        for counters in self.native.get(key, ()):
            for name, _ in counters._fields_:
                value = getattr(counters, name)
                if name == "last_seq":
                    topic[name] = value or topic[name]
                else:
                    topic[name] += value
        return topic

    def lines(self) -> list[str]:
        """The table: one line per topic and service."""
        data = self.as_dict()
        out = []
        for key, t in sorted(data["topics"].items()):
            if t["direction"] == "out":
                out.append(f"{key} [{t['state']}] read {t['read']} sent {t['sent']} "
                           f"unmatched {t['unmatched']} rate_limited {t['rate_limited']} "
                           f"overruns {t['overruns']} batches {t['batches']} "
                           f"errors {t['errors']}")
            else:
                out.append(f"{key} [{t['state']}] received {t['received']} published "
                           f"{t['published']} gaps {t['gaps']} superseded {t['superseded']} "
                           f"forced {t['forced']} "
                           f"rate_limited {t['rate_limited']} bad_attachment "
                           f"{t['bad_attachment']} bad_size {t['bad_size']} refused "
                           f"{t['refused']} md_unavailable {t['md_unavailable']} batches "
                           f"{t['batches']} bad_batches {t['bad_batches']}")
        for key, s in sorted(data["services"].items()):
            out.append(f"{key} [{s['state']}] calls {s['calls']} errors {s['errors']} "
                       f"bad_requests {s['bad_requests']}")
        if data["unknown_keys"]:
            out.append(f"samples of topics past the limit of names: {data['unknown_keys']}")
        if data["bad_batches"]:
            out.append(f"malformed batches of topics not set up yet: {data['bad_batches']}")
        return out or ["nothing bridged yet"]

    def write(self, path: str | os.PathLike[str]) -> None:
        """The counters as JSON, replacing `path` atomically."""
        target = Path(path)
        tmp = target.with_name(f".{target.name}.{os.getpid()}.tmp")
        tmp.write_text(json.dumps(self.as_dict(), indent=1, sort_keys=True))
        tmp.replace(target)
