"""Benchmark of ln_bag's streaming commands: throughput and peak memory.

Goals (PASS/MISS in the table):
  1. cut, filter, merge and convert each process their input at >= 0.3x the MB/s of
     `cat FILE > /dev/null` measured in the same run on the same file (the floor: reading
     the bytes and nothing else); `cp FILE NEW` (reading and writing the bytes, what a
     tool that writes its output cannot go below) is shown beside it as a second floor;
  2. memory does not grow with the input: each command's peak RSS on the big input is at
     most 1.25x its peak RSS on an input a quarter of that size (plus 8 MB slack).
Input: a recording written with McapWriter (zstd chunks of 1 MiB, as ln_record writes),
two topics of 4 KiB samples (md lnbench/blob: double values[512], noisy sines) interleaved
in every chunk, 100 MB with --quick, 1 GB without.  The cases: where whole chunks are
copied as stored (cut of a long range, filter keeping every topic, convert to the encoding
the file has) and where every chunk goes sample by sample (filter of one of the two topics:
every chunk mixed; merge; convert ln -> ros2, the worst).  Each command runs as its own
process (`python -m links_and_nodes.bag.cli`, default output options) on the page-cached
file, timed from start to exit, `--repeat` times, median reported; its peak RSS is the
process's ru_maxrss.  The goal is judged on that whole time; "in main()" is the time the
process itself measures around the command, after the interpreter started and imported
ln_bag (at 100 MB start-up is most of a fast-path run), and "start-up" a process that only
imports ln_bag, both in the same run.  Prints a table and writes
bench/results/bag.json and bench/results/bag.md.  A benchmark, not a test: exits 0 whether
goals pass or miss.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(REPO / "python"), str(REPO)]

from links_and_nodes.mcap_format import McapWriter  # noqa: E402

GOAL = ("cut/filter/merge/convert >= 0.3x `cat FILE > /dev/null` MB/s; peak RSS on the big "
        "input <= 1.25x (+8 MB) that on a quarter-size input")
T0 = 1_765_000_000_000_000_000
SAMPLE = 4096
RUNNER = ("import resource, sys, time\nfrom links_and_nodes.bag.cli import main\n"
          "t = time.perf_counter()\ncode = main(sys.argv[1:])\n"
          "print('work', time.perf_counter() - t, file=sys.stderr)\n"
          "print('maxrss', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, "
          "file=sys.stderr)\nsys.exit(code)\n")


MD_TEXT = f"double values[{SAMPLE // 8}]\n"


def _layout_hash(tmp: Path) -> int:
    from ln_generate import MdRegistry

    (tmp / "md" / "lnbench").mkdir(parents=True, exist_ok=True)
    (tmp / "md" / "lnbench" / "blob").write_text(MD_TEXT)
    return int(MdRegistry([tmp / "md"]).load("lnbench/blob").layout_hash)


def make_input(path: Path, size: int) -> int:
    rng = np.random.default_rng(1)
    bodies = [(np.sin(np.arange(SAMPLE // 8) * 0.01 + k) + rng.normal(0, 0.001, SAMPLE // 8))
              .astype("<f8").tobytes() for k in range(64)]
    text = f"--- lnbench/blob\n{MD_TEXT}".encode()
    layout_hash = _layout_hash(path.parent)
    with McapWriter(path, "zstd") as w:
        chans = [w.add_topic(name, "lnbench/blob", text, layout_hash, SAMPLE)
                 for name in ("bench.a", "bench.b")]
        n = 0
        while w.offset < size:
            w.write(chans[n & 1], n // 2 + 1, T0 + n * 1_000_000, bodies[n & 63])
            n += 1
    return n


def run(argv: list[str]) -> tuple[float, int, float]:
    """(seconds, peak RSS in KiB, seconds in main() after the imports) of one ln_bag run."""
    env = {**os.environ, "PYTHONPATH": f"{REPO / 'python'}:{REPO}"}
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", RUNNER, *argv], capture_output=True,
                          text=True, env=env)
    took = time.perf_counter() - start
    if proc.returncode != 0:
        raise SystemExit(f"ln_bag {' '.join(argv)} failed: {proc.stderr}")
    rss = int(proc.stderr.rsplit("maxrss ", 1)[1].split()[0])
    work = float(proc.stderr.rsplit("work ", 1)[1].split()[0])
    return took, rss, work


def cat_seconds(path: Path) -> float:
    start = time.perf_counter()
    with open(os.devnull, "wb") as null:
        subprocess.run(["cat", str(path)], stdout=null, check=True)
    return time.perf_counter() - start


def cp_seconds(path: Path, tmp: Path) -> float:
    copy = tmp / "cp.mcap"
    start = time.perf_counter()
    subprocess.run(["cp", str(path), str(copy)], check=True)
    took = time.perf_counter() - start
    copy.unlink()
    return took


# name -> (path, arguments); path "fast": whole chunks copied, "samples": sample by sample
CASES = {
    "cut +1 s .. end": ("fast", ["cut", "SRC", "--start", "+1"]),
    "filter, every topic": ("fast", ["filter", "SRC", "--exclude", "none"]),
    "convert ln -> ln": ("fast", ["convert", "SRC", "--encoding", "ln"]),
    "filter, 1 of 2 topics": ("samples", ["filter", "SRC", "--topic", "bench.a"]),
    "merge of 2 halves": ("samples", ["merge", "HALF0", "HALF1"]),
    "convert ln -> ros2": ("samples", ["convert", "SRC", "--encoding", "ros2"]),
}


def commands(src: Path, half: tuple[Path, Path], tmp: Path) -> dict[str, list[str]]:
    names = {"SRC": str(src), "HALF0": str(half[0]), "HALF1": str(half[1])}
    return {name: [names.get(a, a) for a in argv] + ["-o", str(tmp / "out.mcap"), "-qf"]
            for name, (_path, argv) in CASES.items()}


def startup_seconds() -> float:
    env = {**os.environ, "PYTHONPATH": f"{REPO / 'python'}:{REPO}"}
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", "import links_and_nodes.bag.cli"], env=env,
                   check=True)
    return time.perf_counter() - start


def measure(size: int, repeat: int, tmp: Path) -> dict[str, dict[str, float]]:
    src = tmp / f"in_{size}.mcap"
    make_input(src, size)
    subprocess.run([sys.executable, "-c", RUNNER, "split", str(src), "-o",
                    str(tmp / f"half_{size}"), "--size", str(size // 2 + (1 << 20)), "-qf"],
                   env={**os.environ, "PYTHONPATH": f"{REPO / 'python'}:{REPO}"}, check=True,
                   capture_output=True)
    halves = (tmp / f"half_{size}_0000.mcap", tmp / f"half_{size}_0001.mcap")
    mb = src.stat().st_size / 1e6
    cat_seconds(src)  # into the page cache
    results = {"cat": {"mb_s": mb / statistics.median(cat_seconds(src) for _ in range(repeat)),
                       "rss_mb": 0.0},
               "cp": {"mb_s": mb / statistics.median(cp_seconds(src, tmp)
                                                     for _ in range(repeat))},
               "start-up": {"s": statistics.median(startup_seconds() for _ in range(repeat))}}
    for name, argv in commands(src, halves, tmp).items():
        runs = [run(argv) for _ in range(repeat)]
        seconds = statistics.median(r[0] for r in runs)
        results[name] = {"mb_s": mb / seconds, "s": seconds,
                         "work_s": statistics.median(r[2] for r in runs),
                         "rss_mb": max(r[1] for r in runs) / 1024}
    for p in (src, *halves, tmp / "out.mcap"):
        p.unlink(missing_ok=True)
    return results


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="100 MB input instead of 1 GB")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    big = (100 if args.quick else 1000) * 1_000_000
    with tempfile.TemporaryDirectory(prefix="bench_bag.") as d:
        small_r = measure(big // 4, args.repeat, Path(d))
        big_r = measure(big, args.repeat, Path(d))
    cat = big_r["cat"]["mb_s"]
    cp = big_r["cp"]["mb_s"]
    startup = big_r["start-up"]["s"]
    mb = big / 1e6
    rows = []
    for name, (path, _argv) in CASES.items():
        b, s = big_r[name], small_r[name]
        ratio = b["mb_s"] / cat
        mem_ok = b["rss_mb"] <= 1.25 * s["rss_mb"] + 8
        rows.append({"command": name, "path": path, "mb_s": round(b["mb_s"], 1),
                     "x_cat": round(ratio, 3), "x_cp": round(b["mb_s"] / cp, 3),
                     "mb_s_in_main": round(mb / b["work_s"], 1),
                     "x_cat_in_main": round(mb / b["work_s"] / cat, 3),
                     "rss_mb": round(b["rss_mb"], 1), "rss_mb_quarter": round(s["rss_mb"], 1),
                     "speed": "PASS" if ratio >= 0.3 else "MISS",
                     "memory": "PASS" if mem_ok else "MISS"})
    lines = [f"ln_bag on a {big // 1_000_000} MB zstd recording (4 KiB samples); "
             f"`cat > /dev/null`: {cat:.0f} MB/s; `cp`: {cp:.0f} MB/s; Python start-up with ln_bag imported: "
             f"{startup:.2f} s", "",
             "| case | path | MB/s | x cat | goal 0.3x | x cp | MB/s in main() | x cat "
             "| peak RSS MB | on 1/4 input | memory |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    lines += [f"| {r['command']} | {r['path']} | {r['mb_s']} | {r['x_cat']} | {r['speed']} | "
              f"{r['x_cp']} | "
              f"{r['mb_s_in_main']} | {r['x_cat_in_main']} | {r['rss_mb']} | "
              f"{r['rss_mb_quarter']} | {r['memory']} |" for r in rows]
    text = "\n".join(lines)
    print(text)
    out = REPO / "bench" / "results"
    out.mkdir(parents=True, exist_ok=True)
    (out / "bag.md").write_text(text + "\n")
    (out / "bag.json").write_text(json.dumps({
        "goal": GOAL, "quick": args.quick, "input_mb": big / 1e6, "repeat": args.repeat,
        "cat_mb_s": round(cat, 1), "cp_mb_s": round(cp, 1), "startup_s": round(startup, 3), "rows": rows, "machine": platform.machine(),
        "cpus": os.cpu_count(), "python": platform.python_version(),
        "self_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}, indent=1)
        + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
