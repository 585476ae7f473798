"""What ln_play does before it plays: check recordings whole (decoding every sample to ln
bytes), check every topic's layout, open the publishers; and the order samples play in
(playback.py plays them).

Nothing is published before every file has been read once without error and every topic has
a publisher whose layout matches the recorded one, so a corrupt file or a changed md never
leaves a half-played recording behind.
"""

from __future__ import annotations

import ctypes
import heapq
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any, NamedTuple, TypeVar

from .. import md_loader
from ..mcap_format import McapReader, Sample, TopicInfo, write_md_files
from .encodings import ln_decoder

REORDER_WINDOW_NS = 1_000_000_000  # how far topics may be out of time order in a file


class PlayError(Exception):
    """Why a recording cannot be played; the text says it all."""


Decoder = tuple[TopicInfo, Callable[[bytes], bytes]]  # a file's channel, its ln decoder


@dataclass
class Recording:
    """The files of one recording, checked: their topics (channels of kind "topic"), the
    other channels (e.g. service calls, `others`), and what they hold.  `decoders[i]` has,
    per channel name, file i's channel and the function from its messages to ln bytes."""

    readers: list[McapReader]
    topics: dict[str, TopicInfo]
    counts: dict[str, int] = field(default_factory=dict)
    first_ns: int | None = None  # of the topics' samples
    last_ns: int | None = None
    notes: list[str] = field(default_factory=list)
    others: dict[str, TopicInfo] = field(default_factory=dict)
    decoders: list[dict[str, Decoder]] = field(default_factory=list)


def file_decoders(reader: McapReader) -> dict[str, Decoder]:
    """Per channel of the file: the channel and the function from its stored messages to ln
    bytes; PlayError naming file and channel for an encoding that cannot be read."""
    out: dict[str, Decoder] = {}
    for name, info in reader.topics().items():
        if info.kind == "service":
            continue  # recorded calls are not ln samples (service_replay.py reads them)
        try:
            out[name] = (info, ln_decoder(info))
        except Exception as exc:  # noqa: BLE001 - EncodingError & co. carry the reason
            raise PlayError(f"{reader.path}: channel '{name}': {exc}") from None
    return out


def decode_sample(path: str, decoders: dict[str, Decoder], n: int, sample: Sample) -> Sample:
    """The sample with its data in ln bytes of the md's size; PlayError with file, channel
    and sample (its place `n` among the file's samples) for one that does not decode."""
    info, decode = decoders[sample.topic]
    try:
        data = decode(sample.data)
        if len(data) != info.message_size:
            raise ValueError(f"{len(data)} bytes decoded, md '{info.md_name}' has "
                             f"{info.message_size}")
    except Exception as exc:  # noqa: BLE001 - any decoder's error, with the place added
        raise PlayError(f"{path}: channel '{sample.topic}' ({info.message_encoding}), sample "
                        f"{n} of the file (sequence {sample.seq}, time "
                        f"{sample.publish_time_ns} ns): cannot decode: {exc}") from None
    return sample._replace(data=bytes(data))


class Stored(NamedTuple):
    """A sample as its file holds it, and where (file index, place in the file), until it is
    decoded: skipping samples (--start, a seek) costs no decoding."""

    topic: str
    publish_time_ns: int
    sample: Sample
    file: int
    n: int


def check_files(paths: list[str], allow_truncated: bool = False) -> Recording:
    """Read every file once (framing, CRCs, sizes, decoding): McapError or PlayError for a
    bad one."""
    readers: list[McapReader] = []
    topics: dict[str, TopicInfo] = {}
    rec = Recording(readers, topics)
    for path in paths:
        reader = McapReader(path, allow_truncated=allow_truncated)
        decoders = file_decoders(reader)
        for n, stored in enumerate(reader.samples()):
            if stored.topic not in decoders:  # a service's calls: counted, not decoded
                rec.counts[stored.topic] = rec.counts.get(stored.topic, 0) + 1
                continue
            sample = decode_sample(reader.path, decoders, n, stored)
            rec.counts[sample.topic] = rec.counts.get(sample.topic, 0) + 1
            if decoders[sample.topic][0].kind != "topic":
                continue
            t = sample.publish_time_ns
            rec.first_ns = t if rec.first_ns is None else min(rec.first_ns, t)
            rec.last_ns = t if rec.last_ns is None else max(rec.last_ns, t)
        for name, info in reader.topics().items():
            known = (topics if info.kind == "topic" else rec.others).setdefault(name, info)
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
        rec.decoders.append(decoders)
    return rec


S = TypeVar("S", Sample, Stored)


def stored_samples(rec: Recording, wanted: list[str]) -> Iterator[Stored]:
    """The samples of the `wanted` topics as stored, file after file (read again from the
    start of the first file on every call)."""
    wanted_set = set(wanted)
    for i, reader in enumerate(rec.readers):
        for n, sample in enumerate(reader.samples()):
            if sample.topic in wanted_set:
                yield Stored(sample.topic, sample.publish_time_ns, sample, i, n)


def decode_stored(rec: Recording, stored: Stored) -> Sample:
    """The stored sample in ln bytes (PlayError naming file, channel and sample)."""
    return decode_sample(rec.readers[stored.file].path, rec.decoders[stored.file], stored.n,
                         stored.sample)


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


def in_time_order(samples: Iterable[S], window_ns: int = REORDER_WINDOW_NS
                  ) -> Iterator[tuple[int, S]]:
    """(play time, sample) in time order across topics.  A file holds each topic's samples
    in order but topics interleaved as the recorder read them: samples are held back until
    `window_ns` of recording time has passed.  A topic's own order is kept even if its
    clock stepped back (its play time never decreases)."""
    heap: list[tuple[int, int, S]] = []
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
