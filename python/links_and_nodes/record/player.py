"""What ln_play does: check recordings whole, check every topic's layout, then publish the
samples again with their recorded relative timing.

Nothing is published before every file has been read once without error and every topic has
a publisher whose layout matches the recorded one, so a corrupt file or a changed md never
leaves a half-played recording behind.
"""

from __future__ import annotations

import ctypes
import heapq
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any

from .. import md_loader
from ..mcap_format import McapReader, Sample, TopicInfo, write_md_files

REORDER_WINDOW_NS = 1_000_000_000  # how far topics may be out of time order in a file


class PlayError(Exception):
    """Why a recording cannot be played; the text says it all."""


@dataclass
class Recording:
    """The files of one recording, checked: their topics and what they hold."""

    readers: list[McapReader]
    topics: dict[str, TopicInfo]
    counts: dict[str, int] = field(default_factory=dict)
    first_ns: int | None = None
    last_ns: int | None = None
    notes: list[str] = field(default_factory=list)


def check_files(paths: list[str], allow_truncated: bool = False) -> Recording:
    """Read every file once (framing, CRCs, sizes): McapError for a bad one."""
    readers: list[McapReader] = []
    topics: dict[str, TopicInfo] = {}
    rec = Recording(readers, topics)
    for path in paths:
        reader = McapReader(path, allow_truncated=allow_truncated)
        for sample in reader:
            rec.counts[sample.topic] = rec.counts.get(sample.topic, 0) + 1
            t = sample.publish_time_ns
            rec.first_ns = t if rec.first_ns is None else min(rec.first_ns, t)
            rec.last_ns = t if rec.last_ns is None else max(rec.last_ns, t)
        for name, info in reader.topics().items():
            known = topics.setdefault(name, info)
            if (known.md_name, known.layout_hash) != (info.md_name, info.layout_hash):
                raise PlayError(f"topic '{name}' has md '{known.md_name}' (layout hash "
                                f"{known.layout_hash:016x}) in one file and '{info.md_name}' "
                                f"({info.layout_hash:016x}) in {path}")
        if reader.truncated_at is not None:
            rec.notes.append(f"{path} is cut short at byte {reader.truncated_at}: playing the "
                             "samples before it")
        elif not reader.complete:
            rec.notes.append(f"{path} has no summary (its recorder did not close it): "
                             "playing every complete chunk")
        readers.append(reader)
    return rec


def _installed_hash(md_name: str) -> int | None:
    """Layout hash of the md of that name as ln_generate finds it here; None if it is not
    found or broken."""
    try:
        return int(md_loader.message_class(md_name).LAYOUT_HASH)
    except Exception:  # noqa: BLE001 - MdError: not installed (or broken) here
        return None


def resolve_classes(topics: dict[str, TopicInfo], schema_dir: str) -> list[str]:
    """Make every topic's md loadable with its recorded layout: an installed md must have
    it; an md that is not installed is taken from the recording (its definition is written
    into `schema_dir`, which is added to the md search path).  Notes for the user; PlayError
    for a mismatch, naming the md and both hashes."""
    notes = []
    missing: dict[str, TopicInfo] = {}
    for info in topics.values():
        here = _installed_hash(info.md_name)
        if here is None:
            missing.setdefault(info.md_name, info)
        elif here != info.layout_hash:
            raise PlayError(f"topic '{info.topic}' was recorded with md '{info.md_name}' of "
                            f"layout hash {info.layout_hash:016x}, but md '{info.md_name}' "
                            f"here has layout hash {here:016x}: refusing to play (nothing "
                            "was published)")
    if missing:
        for md_name, info in missing.items():
            try:
                write_md_files(info.md_text, schema_dir)
            except (ValueError, OSError) as exc:
                raise PlayError(f"topic '{info.topic}': md '{md_name}' is not installed and "
                                f"its recorded definition is unusable: {exc}") from None
            notes.append(f"md '{md_name}' is not installed: using its recorded definition")
        md_loader.add_message_definition_dir(schema_dir)
    for info in topics.values():  # again: the recorded mds may shadow installed imports
        try:
            cls = md_loader.message_class(info.md_name)
        except Exception as exc:  # noqa: BLE001 - MdError of a recorded definition
            raise PlayError(f"topic '{info.topic}': md '{info.md_name}' cannot be loaded: "
                            f"{exc}") from None
        if cls.LAYOUT_HASH != info.layout_hash or ctypes.sizeof(cls) != info.message_size:
            raise PlayError(f"topic '{info.topic}': md '{info.md_name}' has layout hash "
                            f"{cls.LAYOUT_HASH:016x} ({ctypes.sizeof(cls)} bytes) here, the "
                            f"recording says {info.layout_hash:016x} ({info.message_size} "
                            "bytes): refusing to play (nothing was published)")
    return notes


def in_time_order(samples: Iterable[Sample], window_ns: int = REORDER_WINDOW_NS
                  ) -> Iterator[tuple[int, Sample]]:
    """(play time, sample) in time order across topics.  A file holds each topic's samples
    in order but topics interleaved as the recorder read them: samples are held back until
    `window_ns` of recording time has passed.  A topic's own order is kept even if its
    clock stepped back (its play time never decreases)."""
    heap: list[tuple[int, int, Sample]] = []
    last: dict[str, int] = {}
    for n, sample in enumerate(samples):
        t = max(sample.publish_time_ns, last.get(sample.topic, sample.publish_time_ns))
        last[sample.topic] = t
        heapq.heappush(heap, (t, n, sample))
        while heap and heap[0][0] < t - window_ns:
            t0, _, s = heapq.heappop(heap)
            yield t0, s
    while heap:
        t0, _, s = heapq.heappop(heap)
        yield t0, s


class Publisher:
    """A topic's publisher and the memory of its packet."""

    def __init__(self, port: Any) -> None:
        self.port = port
        self.address = ctypes.addressof(port.packet)
        self.size = ctypes.sizeof(port.packet)

    def write(self, data: bytes) -> None:
        ctypes.memmove(self.address, data, self.size)
        self.port.write()


def open_publishers(client: Any, topics: dict[str, TopicInfo], remap: dict[str, str],
                    wait_for_subscribers: bool = False) -> dict[str, Publisher]:
    """A publisher per recorded topic (under its remapped name), after resolve_classes();
    PlayError, with every port closed again, if a publish is refused."""
    ports: dict[str, Publisher] = {}
    try:
        for name, info in topics.items():
            target = remap.get(name, name)
            try:
                port = client.publish(target, info.md_name,
                                      wait_for_subscribers=wait_for_subscribers)
            except Exception as exc:  # noqa: BLE001 - LnLayoutError & co. carry libln's text
                raise PlayError(f"cannot publish topic '{target}' (md '{info.md_name}', "
                                f"recorded layout hash {info.layout_hash:016x}): {exc}; "
                                "nothing was published") from None
            ports[name] = Publisher(port)
    except BaseException:
        for pub in ports.values():
            pub.port.close()
        raise
    return ports


def play(rec: Recording, ports: dict[str, Publisher], rate: float, start_s: float,
         loop: bool, on_sample: Callable[[int], None] | None = None) -> int:
    """Publish the samples of the topics in `ports`, `rate` times as fast as recorded, from
    `start_s` seconds after the recording's first sample; again and again with `loop`.
    Returns how many were published (Ctrl-C ends it with KeyboardInterrupt)."""
    published = 0
    skip_until = (rec.first_ns or 0) + int(start_s * 1e9)
    wanted = list(ports)
    while True:
        wall0 = t0 = None
        for t, sample in in_time_order(s for r in rec.readers for s in r.samples(wanted)):
            if t < skip_until:
                continue
            if t0 is None:
                wall0, t0 = time.monotonic(), t
            delay = wall0 + (t - t0) / 1e9 / rate - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            ports[sample.topic].write(sample.data)
            published += 1
            if on_sample is not None:
                on_sample(published)
        if not loop or t0 is None:
            return published
