"""Benchmark of ln_record's MCAP writer against a plain-write floor and the PyPI mcap writer.

Goals (each PASS/MISS in the table):
  1. ln_record's writer is at least as fast as the PyPI `mcap` writer (the reference
     implementation) in the same run, for every sample size and compression;
  2. uncompressed, it reaches at least half the floor's MB/s for 4 KiB and 1 MiB samples
     (so its per-sample work costs less than the copy to the file does);
  3. uncompressed, recording in the `ros2` encoding (CDR, what viewers decode; the
     recorder's default) also reaches half the floor for 4 KiB and 1 MiB (`json` is shown
     beside it, without a goal).
The floor: the same samples written one by one with a buffered file's write() (1 MiB
buffer), no framing at all.  ln_record's writer: the SplitWriter ln_record uses (one
McapWriter, 1 MiB chunks, message indexes, CRCs, summary); the PyPI writer: mcap.writer.Writer
with the same chunk size, one channel, sequence and times per message.  64 B, 4 KiB and
1 MiB samples, compression none, zstd and lz4; every case writes the same bytes into a file
in a temporary directory (page cache, no fsync) and is timed from the first write to the
closed file, `--repeat` times, median reported.  Samples are 64 different semi-compressible
buffers (a counter, a noisy sine as float64: md `uint64_t counter` + `double wave[N]`) used
in turn; the encoded writers take them through record/encodings.py as ln_record does.  Prints a table and writes
bench/results/record.json.  A benchmark, not a test: exits 0 whether goals pass or miss.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(REPO / "python"), str(REPO)]

from links_and_nodes.mcap_format import DEFAULT_CHUNK_SIZE, join_md_texts  # noqa: E402
from links_and_nodes.record.encodings import channel_encoder  # noqa: E402
from links_and_nodes.record.split_writer import SplitWriter  # noqa: E402

GOAL = ("ln_record's writer >= the PyPI mcap writer for every case; uncompressed >= 0.5x "
        "the plain-write floor for 4 KiB and 1 MiB, in the ln and the ros2 encoding")
SIZES = {"64 B": 64, "4 KiB": 4096, "1 MiB": 1 << 20}
COMPRESSIONS = ("none", "zstd", "lz4")
T0 = 1_700_000_000_000_000_000


def samples(size: int, count: int = 64) -> list[bytes]:
    rng = np.random.default_rng(size)
    out = []
    for k in range(count):
        n = max(0, (size - 8) // 8)
        wave = np.sin(np.arange(n) * 0.01 + k) + rng.normal(0, 0.001, n)
        body = k.to_bytes(8, "little") + wave.astype("<f8").tobytes()
        out.append(body.ljust(size, b"\0")[:size])
    return out


def floor(path: Path, data: list[bytes], n: int, compression: str) -> None:
    with open(path, "wb", buffering=1 << 20) as f:
        write = f.write
        for i in range(n):
            write(data[i & 63])


def ln_writer(path: Path, data: list[bytes], n: int, compression: str) -> None:
    out = SplitWriter(path.parent, path.stem, compression, DEFAULT_CHUNK_SIZE, 1 << 40)
    ch = out.add_topic("bench.topic", "lnbench/sample", b"--- lnbench/sample\n", 0x1234,
                       len(data[0]))
    write = out.write
    for i in range(n):
        write(ch, i + 1, T0 + i * 1000, data[i & 63])
    out.close()


def pypi_writer(path: Path, data: list[bytes], n: int, compression: str) -> None:
    from mcap.writer import CompressionType, Writer

    kind = {"none": CompressionType.NONE, "zstd": CompressionType.ZSTD,
            "lz4": CompressionType.LZ4}[compression]
    with open(path, "wb") as f:
        writer = Writer(f, chunk_size=DEFAULT_CHUNK_SIZE, compression=kind)
        writer.start()
        schema = writer.register_schema("lnbench/sample", "ln-md-text",
                                        b"--- lnbench/sample\n")
        ch = writer.register_channel("bench.topic", "ln-md", schema)
        add = writer.add_message
        for i in range(n):
            t = T0 + i * 1000
            add(ch, t, data[i & 63], t, sequence=(i + 1) & 0xFFFFFFFF)
        writer.finish()


def bench_md(size: int) -> tuple[str, bytes, int]:
    """(md name, ln-md-text, layout hash) of the benchmark samples of `size` bytes."""
    import tempfile as tf

    from links_and_nodes.ros2.types import load_md

    text = f"uint64_t counter\ndouble wave[{max(1, (size - 8) // 8)}]\n".encode()
    with tf.TemporaryDirectory() as md_dir:
        Path(md_dir, "lnbench").mkdir()
        Path(md_dir, "lnbench", "sample").write_bytes(text)
        md = load_md("lnbench/sample", [md_dir])
        assert md.struct.size == size, (md.struct.size, size)
        return md.name, join_md_texts([(md.name, text)]), md.layout_hash


def encoded_writer(encoding: str) -> Callable[[Path, list[bytes], int, str], None]:
    def run(path: Path, data: list[bytes], n: int, compression: str) -> None:
        name, text, layout_hash = bench_md(len(data[0]))
        enc = channel_encoder(encoding, name, text, layout_hash, len(data[0]))
        out = SplitWriter(path.parent, path.stem, compression, DEFAULT_CHUNK_SIZE, 1 << 40)
        ch = out.add_channel("bench.topic", enc)
        write, encode = out.write, enc.encode
        for i in range(n):
            write(ch, i + 1, T0 + i * 1000, encode(data[i & 63]))
        out.close()
    return run


ENCODED = {"ln_record ros2": encoded_writer("ros2"), "ln_record json": encoded_writer("json")}

WRITERS: dict[str, Callable[[Path, list[bytes], int, str], None]] = {
    "floor: write()": floor, "ln_record writer": ln_writer, "PyPI mcap writer": pypi_writer,
    **ENCODED}


def timed(fn: Callable[[Path, list[bytes], int, str], None], tmp: Path, data: list[bytes],
          n: int, compression: str) -> tuple[float, int]:
    path = tmp / "out.mcap"
    for old in tmp.iterdir():
        old.unlink()
    start = time.perf_counter()
    split = fn is ln_writer or fn in ENCODED.values()
    fn(tmp / "out" if split else path, data, n, compression)
    elapsed = time.perf_counter() - start
    size = sum(p.stat().st_size for p in tmp.iterdir())
    return elapsed, size


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mbytes", type=int, default=256,
                        help="payload MB per case for 4 KiB and 1 MiB (256); 64 B: a quarter")
    parser.add_argument("--repeat", type=int, default=3, help="runs per case (3)")
    parser.add_argument("--quick", action="store_true", help="a tenth of the data, 1 run")
    parser.add_argument("--json", type=Path, default=REPO / "bench" / "results" / "record.json")
    args = parser.parse_args()
    if args.quick:
        args.mbytes, args.repeat = max(1, args.mbytes // 10), 1
    try:
        import mcap  # noqa: F401
    except ImportError:
        sys.exit("bench_record: the PyPI package mcap is missing (bash scripts/setup)")

    cpus, usable = os.cpu_count(), len(os.sched_getaffinity(0))
    print(f"goal: {GOAL}")
    print(f"cpu: os.cpu_count()={cpus}, usable (sched_getaffinity)={usable}")
    results: list[dict[str, object]] = []
    with tempfile.TemporaryDirectory(prefix="ln_bench_record_") as tmp_name:
        tmp = Path(tmp_name)
        for size_label, size in SIZES.items():
            data = samples(size)
            total = args.mbytes * 1_000_000 // (4 if size == 64 else 1)
            n = max(1, total // size)
            for compression in COMPRESSIONS:
                for label, fn in WRITERS.items():
                    if (fn is floor or fn in ENCODED.values()) and compression != "none":
                        continue
                    timed(fn, tmp, data, min(n, 1000), compression)  # warm-up
                    runs = [timed(fn, tmp, data, n, compression) for _ in range(args.repeat)]
                    times = [t for t, _ in runs]
                    med = statistics.median(times)
                    results.append({
                        "size": size_label, "sample_bytes": size, "compression": compression,
                        "writer": label, "samples": n, "payload_bytes": n * size,
                        "file_bytes": runs[-1][1], "median_s": med, "runs_s": times,
                        "mb_per_s": n * size / med / 1e6, "samples_per_s": n / med})
    verdicts = judge(results)
    print(f"\n{'size':<7}{'compr':<6}{'writer':<18}{'samples':>9}{'MB/s':>9}{'samples/s':>12}"
          f"{'file MB':>9}  goal")
    for r in results:
        print(f"{r['size']:<7}{r['compression']:<6}{r['writer']:<18}{r['samples']:>9}"
              f"{r['mb_per_s']:>9.1f}{r['samples_per_s']:>12.0f}"
              f"{r['file_bytes'] / 1e6:>9.1f}  {verdicts.get(id(r), '')}")
    args.json.parent.mkdir(parents=True, exist_ok=True)
    for r in results:
        r["goal"] = verdicts.get(id(r))
    args.json.write_text(json.dumps({
        "goal": GOAL, "repeat": args.repeat, "mbytes": args.mbytes, "cpu_count": cpus,
        "usable_cpus": usable, "python_version": platform.python_version(),
        "machine": platform.machine(), "timestamp": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "results": results}, indent=2) + "\n")
    print(f"\nwrote {args.json}")
    return 0


def judge(results: list[dict[str, object]]) -> dict[int, str]:
    """PASS/MISS per ln_record row: the ratio to the PyPI writer (and to the floor where
    goal 2 applies)."""
    by = {(r["size"], r["compression"], r["writer"]): r for r in results}
    out = {}
    for r in results:
        if r["writer"] == "ln_record ros2" and r["size"] != "64 B":
            fl = float(by[(r["size"], "none", "floor: write()")]["mb_per_s"])  # type: ignore[arg-type]
            ratio = float(r["mb_per_s"]) / fl  # type: ignore[arg-type]
            out[id(r)] = f"{'PASS' if ratio >= 0.5 else 'MISS'} ({ratio:.2f}x floor)"
        if r["writer"] != "ln_record writer":
            continue
        ours = float(r["mb_per_s"])  # type: ignore[arg-type]
        pypi = float(by[(r["size"], r["compression"], "PyPI mcap writer")]["mb_per_s"])  # type: ignore[arg-type]
        ok = ours >= pypi
        text = f"{ours / pypi:.2f}x PyPI"
        if r["compression"] == "none" and r["size"] != "64 B":
            fl = float(by[(r["size"], "none", "floor: write()")]["mb_per_s"])  # type: ignore[arg-type]
            ok = ok and ours >= 0.5 * fl
            text += f", {ours / fl:.2f}x floor"
        out[id(r)] = f"{'PASS' if ok else 'MISS'} ({text})"
    return out


if __name__ == "__main__":
    sys.exit(main())
