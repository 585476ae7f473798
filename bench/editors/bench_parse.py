"""Benchmark of the Tree-sitter grammars under editors/ over the real Links and Nodes corpus.

Goal: Tree-sitter parses the whole real corpus (../shared/real_ln: lnc/ with tree-sitter-lnc,
md/ with tree-sitter-lnmd) in under 50 ms. Each grammar's src/ is compiled with `cc -O2`
and loaded with the PyPI `tree-sitter` bindings. Each run reads every file's bytes and
parses them; the baseline, timed in the same runs, only reads the bytes. Prints a table of
medians and writes it with every run to bench/results/editors_parse.{txt,json}.
A benchmark, not a test: exits 0 whether the goal passes or misses.
"""

from __future__ import annotations

import argparse
import ctypes
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
REAL_LN = REPO.parent / "shared" / "real_ln"
GOAL = "the whole real corpus parsed in under 50 ms"
GOAL_SECONDS = 0.050
#: grammar (editors/tree-sitter-NAME) -> the corpus folder it parses
CORPORA = {"lnc": REAL_LN / "lnc", "lnmd": REAL_LN / "md"}
CAPSULE_NAME = b"tree_sitter.Language"  # lives as long as the capsules made with it


def load_language(name: str, out_dir: Path) -> Any:
    """The tree_sitter.Language of editors/tree-sitter-NAME, compiled from its src/."""
    import tree_sitter

    src = REPO / "editors" / f"tree-sitter-{name}" / "src"
    sources = [str(p) for p in (src / "parser.c", src / "scanner.c") if p.is_file()]
    library = out_dir / f"tree-sitter-{name}.so"
    subprocess.run(
        ["cc", "-shared", "-fPIC", "-O2", f"-I{src}", *sources, "-o", str(library)], check=True
    )
    entry = getattr(ctypes.CDLL(str(library)), f"tree_sitter_{name}")
    entry.restype = ctypes.c_void_p
    capsule_new = ctypes.pythonapi.PyCapsule_New  # the bindings take the pointer in a capsule
    capsule_new.restype = ctypes.py_object
    capsule_new.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_void_p]
    return tree_sitter.Language(capsule_new(entry(), CAPSULE_NAME, None))


def read_all(files: list[Path]) -> list[bytes]:
    return [path.read_bytes() for path in files]


def timed(work: Callable[[], object]) -> float:
    start = time.perf_counter()
    work()
    return time.perf_counter() - start


def error_count(parser: Any, files: list[Path]) -> int:
    """How many files have an ERROR or MISSING node (the tests name them)."""
    return sum(parser.parse(path.read_bytes()).root_node.has_error for path in files)


def measure(language: Any, files: list[Path], runs: int) -> dict[str, Any]:
    import tree_sitter

    parser = tree_sitter.Parser(language)

    def read_and_parse() -> None:
        for data in read_all(files):
            parser.parse(data)

    read_and_parse()  # warm-up: page cache, first allocations
    parse_times, read_times = [], []
    for _ in range(runs):  # interleaved, so both see the same machine load
        read_times.append(timed(lambda: read_all(files)))
        parse_times.append(timed(read_and_parse))
    return {
        "files": len(files),
        "bytes": sum(p.stat().st_size for p in files),
        "files_with_errors": error_count(parser, files),
        "read_median_s": statistics.median(read_times),
        "read_and_parse_median_s": statistics.median(parse_times),
        "read_and_parse_min_s": min(parse_times),
        "read_and_parse_max_s": max(parse_times),
        "read_runs_s": read_times,
        "read_and_parse_runs_s": parse_times,
    }


def table(results: dict[str, dict[str, Any]], total: float) -> str:
    rows = [
        f"{'grammar':<8} {'files':>5} {'KiB':>6} {'read (base)':>12} "
        f"{'read+parse':>11} {'parse only':>11} {'min..max':>15} {'errors':>6}"
    ]
    for name, r in results.items():
        parse_only = r["read_and_parse_median_s"] - r["read_median_s"]
        rows.append(
            f"{name:<8} {r['files']:>5} {r['bytes'] / 1024:>6.1f} "
            f"{r['read_median_s'] * 1e3:>9.2f} ms {r['read_and_parse_median_s'] * 1e3:>8.2f} ms "
            f"{parse_only * 1e3:>8.2f} ms "
            f"{r['read_and_parse_min_s'] * 1e3:>6.2f}..{r['read_and_parse_max_s'] * 1e3:.2f} ms "
            f"{r['files_with_errors']:>6}"
        )
    verdict = "PASS" if total < GOAL_SECONDS else "MISS"
    rows.append(
        f"whole corpus, read+parse (sum of medians): {total * 1e3:.2f} ms  goal: {GOAL}: {verdict}"
    )
    return "\n".join(rows)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=50, help="timed runs per grammar (50)")
    parser.add_argument("--quick", action="store_true", help="smoke run: 5 runs")
    parser.add_argument(
        "--out",
        type=Path,
        default=REPO / "bench" / "results" / "editors_parse",
        help="results without suffix: .txt (table) and .json",
    )
    args = parser.parse_args()
    runs = 5 if args.quick else args.runs
    try:
        import tree_sitter
    except ImportError:
        sys.exit("the tree-sitter Python package is missing (requirements-dev.txt)")

    results: dict[str, dict[str, Any]] = {}
    missing = []
    with tempfile.TemporaryDirectory(prefix="ln_bench_ts_") as tmp:
        for name, corpus in CORPORA.items():
            if not (REPO / "editors" / f"tree-sitter-{name}" / "src" / "parser.c").is_file():
                missing.append(f"editors/tree-sitter-{name} has no generated src/parser.c")
                continue
            if not corpus.is_dir():
                missing.append(f"corpus {corpus} is not here")
                continue
            files = sorted(p for p in corpus.rglob("*") if p.is_file())
            results[name] = measure(load_language(name, Path(tmp)), files, runs)
    for why in missing:
        print(f"left out: {why}")
    total = sum(r["read_and_parse_median_s"] for r in results.values())
    text = table(results, total)
    print(text)
    print(
        f"{runs} runs per grammar after one warm-up; tree-sitter {tree_sitter.__version__}, "
        f"Python {platform.python_version()}, {os.cpu_count()} CPUs "
        f"({len(os.sched_getaffinity(0))} usable)"
    )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.with_suffix(".txt").write_text(text + "\n")
    args.out.with_suffix(".json").write_text(
        json.dumps(
            {
                "goal": GOAL,
                "goal_s": GOAL_SECONDS,
                "total_read_and_parse_s": total,
                "pass": total < GOAL_SECONDS and not missing,
                "left_out": missing,
                "runs": runs,
                "tree_sitter": tree_sitter.__version__,
                "python": platform.python_version(),
                "cpus": os.cpu_count(),
                "cpus_usable": len(os.sched_getaffinity(0)),
                "results": results,
            },
            indent=2,
        )
        + "\n"
    )
    print(f"\nwrote {args.out.with_suffix('.txt')} and .json")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
