"""CDR codec benchmark (python/links_and_nodes/ros2/cdr.py): what turning an ln sample into
ROS 2 CDR and back costs, for recordings in the `ros2` encoding and ln_zenoh --ros2.

Goal, measured against `bytes(raw)` of a bytearray (one copy of the sample) in the same run: encode+decode
of a 1 MiB sample <= 4x the copy (the codec copies the data twice: once each way), and of a
64 B sample <= 3 us (there the Python call dominates).  Three layouts per size: `aligned`
(double[N]: one copy run), `mixed` (double, uint32, uint8, then double[N]: three runs with
padding), `string` (double, char[32] with 20 bytes of text, double[N]: a data-dependent
position).  Prints a table, writes it to bench/results/cdr.txt and the numbers to cdr.json, exits 0 whether goals are met.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
sys.path.insert(0, str(REPO / "python"))  # measure this checkout, not an installed one
sys.path.insert(0, str(REPO))

from links_and_nodes import ros2  # noqa: E402

SIZES = {"64 B": 64, "4 KiB": 4096, "1 MiB": 1 << 20}
GOAL_BIG_RATIO = 4.0
GOAL_SMALL_NS = 3_000
LAYOUTS = {  # name -> (md text with {n}, fixed bytes besides the double array)
    "aligned": ("double v[{n}]\n", 0),
    "mixed": ("double t\nuint32_t cycle\nuint8_t mode\ndouble v[{n}]\n", 13),
    "string": ("double t\nchar name[32]\ndouble v[{n}]\n", 40),
}


def per_call_ns(fn: Any, arg: Any, budget_s: float) -> float:
    """Best of 5 rounds of the mean ns per call, each round ~budget_s / 5."""
    n = 1
    while True:  # calibrate: n calls take about a round's share of the budget
        t0 = time.perf_counter()
        for _ in range(n):
            fn(arg)
        if time.perf_counter() - t0 >= budget_s / 10:
            break
        n *= 2
    best = float("inf")
    for _ in range(5):
        t0 = time.perf_counter_ns()
        for _ in range(n):
            fn(arg)
        best = min(best, (time.perf_counter_ns() - t0) / n)
    return best


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="short rounds (about 10 s in all)")
    args = ap.parse_args()
    budget = 0.3 if args.quick else 2.0
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench_cdr.") as md_dir:
        Path(md_dir, "bench").mkdir()
        for size_name, size in SIZES.items():
            for layout, (text, fixed) in LAYOUTS.items():
                n = max(1, (size - fixed) // 8)
                name = f"bench/{layout}_{n}"
                Path(md_dir, name).write_text(text.format(n=n))
                c = ros2.codec(name, [md_dir])
                raw = bytearray(c.message_size)
                if layout == "string":
                    raw[8:28] = b"twenty bytes of text"
                raw = bytearray(raw)  # bytes(raw) of a bytearray copies (of bytes it would not)
                cdr = c.encode(raw)
                assert c.decode(cdr) == raw
                copy = per_call_ns(bytes, raw, budget)
                enc = per_call_ns(c.encode, raw, budget)
                dec = per_call_ns(c.decode, cdr, budget)
                rows.append({"size": size_name, "layout": layout, "message_size": len(raw),
                             "copy_ns": copy, "encode_ns": enc, "decode_ns": dec,
                             "ratio": (enc + dec) / copy})
    lines = [f"{'size':>6} {'layout':>8} {'bytes':>8} {'copy ns':>9} {'encode ns':>10} "
             f"{'decode ns':>10} {'enc+dec/copy':>13}"]
    for r in rows:
        lines.append(f"{r['size']:>6} {r['layout']:>8} {r['message_size']:>8} "
                     f"{r['copy_ns']:>9.0f} {r['encode_ns']:>10.0f} {r['decode_ns']:>10.0f} "
                     f"{r['ratio']:>13.2f}")
    big = [r for r in rows if r["size"] == "1 MiB"]
    small = [r for r in rows if r["size"] == "64 B"]
    goals = {
        f"1 MiB enc+dec <= {GOAL_BIG_RATIO}x copy": all(r["ratio"] <= GOAL_BIG_RATIO
                                                        for r in big),
        f"64 B enc+dec <= {GOAL_SMALL_NS} ns": all(r["encode_ns"] + r["decode_ns"]
                                                   <= GOAL_SMALL_NS for r in small),
    }
    lines += [f"goal {goal}: {'met' if met else 'NOT met'}" for goal, met in goals.items()]
    print("\n".join(lines))
    (REPO / "bench" / "results" / "cdr.txt").write_text("\n".join(lines) + "\n")
    out = REPO / "bench" / "results" / "cdr.json"
    out.write_text(json.dumps({"quick": args.quick, "python": platform.python_version(),
                               "machine": platform.machine(), "rows": rows, "goals": goals},
                              indent=1) + "\n")
    print(f"wrote {out.relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
