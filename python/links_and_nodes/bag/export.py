"""`ln_bag export`: the samples of each topic as columns (flatten.py): `--csv DIR` writes
DIR/TOPIC.csv per topic, `--npz FILE` one array per topic (and `__topics__`, a JSON
description).  Streaming: CSV rows go out in batches; an npz's arrays are collected in
temporary files beside it and copied into the zip at the end."""

from __future__ import annotations

import argparse
import csv
import json
import os
import shutil
import tempfile
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

import numpy as np

from ..logger_files import SAMPLE_HEAD
from ..mcap_format import TopicInfo
from ..record.encodings import ln_decoder
from .copying import say
from .errors import BagError
from .flatten import cell, flat_dtype, md_dtype
from .output import check_output
from .progress import Progress
from .selection import Selection, add_selection_args
from .source import Source, first_error

HELP = "write each topic's fields as CSV columns (--csv DIR) or numpy arrays (--npz FILE)"
BATCH = 1 << 20  # bytes of samples converted at a time


def add_arguments(ap: argparse.ArgumentParser) -> None:
    to = ap.add_mutually_exclusive_group(required=True)
    to.add_argument("--csv", metavar="DIR", help="one TOPIC.csv per topic in DIR")
    to.add_argument("--npz", metavar="FILE", help="one array per topic in FILE")
    ap.add_argument("-f", "--force", action="store_true", help="replace existing outputs")
    add_selection_args(ap)


def file_name(topic: str) -> str:
    return topic.replace("/", "_") or "_"


class Column:
    """One topic's output: its columns, its decoder and the batch not written yet."""

    def __init__(self, info: TopicInfo, sink: IO[Any], csv_out: bool) -> None:
        self.info = info
        self.dtype = flat_dtype(md_dtype(info))
        try:
            self.decode: Callable[[bytes], bytes] = ln_decoder(info)
        except ValueError as exc:
            raise BagError(f"topic '{info.topic}': {exc}") from None
        self.sink = sink
        self.csv = csv.writer(sink) if csv_out else None
        self.batch = bytearray()
        self.count = 0
        if self.csv is not None:
            self.csv.writerow(self.dtype.names)

    def add(self, seq: int, t: int, data: bytes) -> None:
        raw = self.decode(data)
        if len(raw) != self.info.message_size:
            raise BagError(f"topic '{self.info.topic}': a sample has {len(raw)} bytes, its md "
                           f"'{self.info.md_name}' {self.info.message_size}")
        self.batch += SAMPLE_HEAD.pack(seq, t)
        self.batch += raw
        self.count += 1
        if len(self.batch) >= BATCH:
            self.flush()

    def flush(self) -> None:
        if self.csv is None:
            self.sink.write(self.batch)
        elif self.batch:
            rows = np.frombuffer(bytes(self.batch), self.dtype).tolist()
            self.csv.writerows([cell(v) for v in row] for row in rows)
        self.batch.clear()


def _sink(args: argparse.Namespace, tmp: Path | None, info: TopicInfo) -> IO[Any]:
    if tmp is not None:
        return open(tmp / f"{len(os.listdir(tmp))}.bin", "w+b")  # noqa: SIM115
    path = Path(args.csv, file_name(info.topic) + ".csv")
    check_output(path, args.inputs, args.force)
    return open(path, "w", newline="")  # noqa: SIM115 - closed by run()


def _write_npz(path: str, columns: list[Column]) -> None:
    described = {c.info.topic: {"md_name": c.info.md_name, "samples": c.count,
                                "layout_hash": f"{c.info.layout_hash:016x}",
                                "message_size": c.info.message_size} for c in columns}
    with zipfile.ZipFile(path, "w", zipfile.ZIP_STORED, allowZip64=True) as zf:
        for c in columns:
            c.sink.seek(0)
            with zf.open(file_name(c.info.topic) + ".npy", "w", force_zip64=True) as f:
                np.lib.format.write_array_header_2_0(f, {
                    "descr": np.lib.format.dtype_to_descr(c.dtype), "fortran_order": False,
                    "shape": (c.count,)})
                shutil.copyfileobj(c.sink, f, 1 << 20)
        meta = np.frombuffer(json.dumps(described).encode(), dtype=np.uint8)
        with zf.open("__topics__.npy", "w") as f:
            np.lib.format.write_array(f, meta)


def run(args: argparse.Namespace) -> int:
    selected = Selection(args)
    if args.npz:
        check_output(args.npz, args.inputs, args.force)
        tmp_dir = tempfile.TemporaryDirectory(prefix=".ln_bag.", dir=Path(args.npz).parent)
        tmp: Path | None = Path(tmp_dir.name)
    else:
        Path(args.csv).mkdir(parents=True, exist_ok=True)
        tmp = None
    sources = [Source(p) for p in args.inputs]
    columns: dict[str, Column] = {}
    progress = Progress("ln_bag export", enabled=None if not args.quiet else False)
    try:
        for src in sources:
            for info, s in src:
                if not selected(info.topic):
                    continue
                col = columns.get(info.topic)
                if col is None:
                    col = columns[info.topic] = Column(info, _sink(args, tmp, info), not tmp)
                col.add(s.seq, s.publish_time_ns, s.data)
                progress.add(len(s.data))
            if src.error is not None:
                break
        for col in columns.values():
            col.flush()
        if args.npz:
            _write_npz(args.npz, list(columns.values()))
    finally:
        progress.done()
        for col in columns.values():
            col.sink.close()
        if tmp is not None:
            tmp_dir.cleanup()
    say(args, f"{sum(c.count for c in columns.values())} samples of {len(columns)} topics "
        f"into {args.npz or args.csv}")
    error = first_error(sources)
    if error is not None:
        raise BagError(f"{error} (the export holds the samples before it)")
    return 0
