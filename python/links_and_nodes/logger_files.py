"""What a logger download becomes (docs/logging.md, "Downloads and files"): per topic a
numpy structured array with the md's fields plus `seq` and `publish_time` (ns), and files:
`.npz` (one array per topic, plus a JSON description under `__loggers__`) or `.mcap` (the
mapping of recording, mcap_format).  Used by the manager (`logger NAME save FILE`) and by
the Python client's `logger.download()` / `logger.save()`.

A download is topic -> {md_name, layout_hash, message_size, samples: [(seq, time_ns,
bytes)] in publish order, hosts, received, missed, skipped, dropped, gaps, divisor}; `gaps`
(the kept sequence numbers missing in the download, host by host) equals `missed` with
divisor 1, and is at most `missed` otherwise."""

from __future__ import annotations

import base64
import json
import struct
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # numpy is imported by the functions that build arrays, so that the
    import numpy as np  # manager, which only collects downloads, starts without it

HEAD_FIELDS = [("seq", "<u8"), ("publish_time", "<i8")]
SAMPLE_HEAD = struct.Struct("<Qq")
FETCH_MAX = 512 * 1024  # sample bytes in one logger_fetch answer (base64 fits in 1 MiB)


def pack_samples(samples: list[tuple[int, int, bytes]]) -> bytes:
    """(seq, time_ns, bytes) samples as packed records, as logger_fetch carries them."""
    return b"".join(SAMPLE_HEAD.pack(seq, t) + data for seq, t, data in samples)


def unpack_samples(blob: bytes, message_size: int) -> list[tuple[int, int, bytes]]:
    step = SAMPLE_HEAD.size + message_size
    if len(blob) % step:
        raise ValueError(f"{len(blob)} bytes of samples are no multiple of {step}")
    return [(*SAMPLE_HEAD.unpack_from(blob, at), blob[at + SAMPLE_HEAD.size:at + step])
            for at in range(0, len(blob), step)]


def new_entry(md_name: str, layout_hash: int, message_size: int, divisor: int
              ) -> dict[str, Any]:
    """An empty download entry of one topic."""
    return {"md_name": md_name, "layout_hash": layout_hash, "message_size": message_size,
            "samples": [], "hosts": [], "received": 0, "missed": 0, "skipped": 0,
            "dropped": 0, "gaps": 0, "divisor": divisor}


def host_gaps(seqs: list[int], start_seq: int, divisor: int, dropped: int) -> int:
    """Kept-sample sequence numbers (multiples of the divisor) missing among one host's
    samples: from the capture's start (or, once depth or span evicted some, from the oldest
    kept one) to the newest.  What the logger missed, as the download sees it."""
    if not seqs:
        return 0
    k = max(1, divisor)
    low = start_seq if dropped == 0 else seqs[0] - 1
    return max(0, seqs[-1] // k - min(low, seqs[0] - 1) // k - len(seqs))


def add_host(entry: dict[str, Any], host: str, samples: list[tuple[int, int, bytes]],
             counters: dict[str, int]) -> None:
    """One host's samples and counters (received, missed, skipped, dropped, start_seq) into
    a topic's download entry."""
    entry["hosts"].append(host)
    entry["samples"].extend(samples)
    for key in ("received", "missed", "skipped", "dropped"):
        entry[key] += counters[key]
    entry["gaps"] += host_gaps([seq for seq, _, _ in samples], counters["start_seq"],
                               entry["divisor"], counters["dropped"])


def download(call: Callable[..., dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """A logger's samples through `call(op, **args)`, a control command on the logger (the
    Python client's or the scripting API's): every topic on every host, chunk by chunk up
    to what each buffer held at its first chunk, merged in publish order."""
    out: dict[str, dict[str, Any]] = {}
    for t in call("logger_status")["topics"]:
        topic, host = t["topic"], t["host"]
        entry = out.setdefault(topic, new_entry(t["md_name"], int(t["layout_hash"], 16),
                                                t["message_size"], t["divisor"]))
        samples: list[tuple[int, int, bytes]] = []
        after, until = 0, None
        while True:
            chunk = call("logger_fetch", topic=topic, host=host, after=after,
                         max_bytes=FETCH_MAX)
            until = chunk["last_seq"] if until is None else until
            got = unpack_samples(base64.b64decode(chunk["samples"]), chunk["message_size"])
            samples.extend(s for s in got if s[0] <= until)
            if not got or got[-1][0] >= until:
                break
            after = got[-1][0]
        add_host(entry, host, samples, chunk)
    for entry in out.values():
        entry["samples"].sort(key=lambda s: (s[1], s[0]))
    return out


def message_dtype(md_name: str, message_size: int) -> np.dtype:
    """The md's fields as a numpy dtype; one opaque `data` field if the md cannot be
    loaded here (or its layout does not have the size the samples have)."""
    import numpy as np

    try:
        from .md_loader import message_class

        dtype = np.dtype(message_class(md_name))
        if dtype.itemsize == message_size:
            return dtype
    except Exception:  # noqa: BLE001 - an md this host cannot read: keep the bytes
        pass
    return np.dtype([("data", f"V{message_size}")])


def sample_dtype(md_name: str, message_size: int) -> np.dtype:
    """`seq`, `publish_time`, then the md's fields at their offsets + 16."""
    import numpy as np

    inner = message_dtype(md_name, message_size)
    names = [n for n, _ in HEAD_FIELDS] + list(inner.names or ())
    formats = [f for _, f in HEAD_FIELDS] + [inner.fields[n][0] for n in inner.names or ()]
    offsets = [0, 8] + [16 + inner.fields[n][1] for n in inner.names or ()]
    return np.dtype({"names": names, "formats": formats, "offsets": offsets,
                     "itemsize": 16 + message_size})


def to_array(entry: dict[str, Any]) -> np.ndarray:
    import numpy as np

    dtype = sample_dtype(entry["md_name"], entry["message_size"])
    blob = pack_samples(entry["samples"])
    return np.frombuffer(blob, dtype=dtype).copy() if blob else np.zeros(0, dtype)


def describe(download: dict[str, dict[str, Any]]) -> dict[str, Any]:
    return {topic: {"md_name": e["md_name"], "layout_hash": f"{e['layout_hash']:016x}",
                    "message_size": e["message_size"], "hosts": e["hosts"],
                    "samples": len(e["samples"]), "received": e["received"],
                    "missed": e["missed"], "skipped": e["skipped"], "dropped": e["dropped"],
                    "gaps": e["gaps"]}
            for topic, e in download.items()}


#: the encoding of an .mcap when none is asked for: the one viewers decode, as ln_record's
DEFAULT_ENCODING = "ros2"


def save(download: dict[str, dict[str, Any]], path: Path, encoding: str | None = None
         ) -> dict[str, Any]:
    """Write a download to `path` (.mcap or .npz); what was written.  encoding: of an .mcap
    (docs/recording.md, "Encodings"): "ros2" (None: the default), "json" or "ln"; a topic
    whose md is not here or that the encoding refuses is stored in "ln" (its entry's
    `encoding` says so).  An .npz holds arrays: encoding None or "ln"."""
    import numpy as np

    path = Path(path)
    suffix = path.suffix.lower()
    used: dict[str, str] = {}
    if encoding is None:
        encoding = "ln" if suffix == ".npz" else DEFAULT_ENCODING
    if suffix == ".npz" and encoding != "ln":
        raise ValueError(f"encoding {encoding!r} is for .mcap files; an .npz holds arrays")
    if suffix == ".npz":
        arrays = {topic: to_array(e) for topic, e in download.items()}
        meta = np.frombuffer(json.dumps(describe(download)).encode(), dtype=np.uint8)
        with open(path, "wb") as f:
            np.savez(f, __loggers__=meta, **arrays)
    elif suffix == ".mcap":
        from .mcap_format import McapWriter

        encoders = {topic: _encoder(e, encoding) for topic, e in download.items()}
        writer = McapWriter(path)
        try:
            for topic, e in download.items():
                enc = encoders[topic]
                if enc is None:
                    channel = writer.add_topic(topic, e["md_name"], _schema(e["md_name"]),
                                               e["layout_hash"], e["message_size"])
                else:
                    channel = enc.add_to(writer, topic)
                encode = enc.encode if enc is not None else bytes
                used[topic] = enc.encoding if enc is not None else "ln"
                for seq, t, data in e["samples"]:
                    writer.write(channel, seq, t, encode(data))
        finally:
            writer.close()
    else:
        raise ValueError(f"unknown file type {suffix or '(none)'!r}: name it .mcap or .npz")
    topics = describe(download)
    for topic, enc_name in used.items():
        topics[topic]["encoding"] = enc_name
    return {"path": str(path), "topics": topics}


def _encoder(entry: dict[str, Any], encoding: str) -> Any:
    """The ChannelEncoder of a topic in `encoding`; None: raw ln bytes (encoding "ln", or an
    md this host does not have or the encoding refuses)."""
    from .record.encodings import ENCODINGS, EncodingError, channel_encoder

    if encoding not in ENCODINGS:
        raise ValueError(f"unknown encoding {encoding!r}: one of {', '.join(ENCODINGS)}")
    text = _schema(entry["md_name"])
    if encoding == "ln" or not text:
        return None
    try:
        return channel_encoder(encoding, entry["md_name"], text, entry["layout_hash"],
                               entry["message_size"])
    except EncodingError:
        return None


def _schema(md_name: str) -> bytes:
    """The md text (with what it imports) for an MCAP schema; empty if this host does not
    have the md (a reader then needs the md installed to decode)."""
    from .mcap_format import md_schema_text

    try:
        return md_schema_text(md_name)
    except Exception:  # noqa: BLE001 - an md only the publisher's host has
        return b""


def load_npz(path: Path) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """The arrays and the description of a saved .npz."""
    import numpy as np

    with np.load(path, allow_pickle=False) as f:
        meta = json.loads(bytes(f["__loggers__"]).decode())
        return {k: f[k] for k in f.files if k != "__loggers__"}, meta
