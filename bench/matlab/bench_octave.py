"""Benchmark of the MATLAB/Octave client (docs/matlab.md, "Performance").

Goal: show what a control engineer's Octave loop pays per sample: write + read of a 64-byte
sample per call (us) against a plain Octave function call measured in the same run (the
baseline: the interpreter's own cost of one call), and the rate a 1 kHz write + read + pause
loop achieves.  Writes a table (bench/results/matlab.md) and JSON (bench/results/matlab.json).
--quick: fewer calls and a 1 s loop (what the tests and a quick check run).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import uuid
from pathlib import Path

from links_and_nodes.manager.frontends import launch

REPO = Path(__file__).resolve().parents[2]
RESULTS = REPO / "bench" / "results"
MDS = REPO / "tests" / "fixtures" / "md" / "matlab"


def run(calls: int, seconds: float) -> dict[str, float]:
    octave = shutil.which("octave-cli")
    if octave is None:
        sys.exit("bench_octave: octave-cli is not installed (apt-get install octave)")
    os.environ["LN_MESSAGE_DEFINITION_DIRS"] = str(MDS)
    instance = f"bench{uuid.uuid4().hex[:8]}"
    with tempfile.TemporaryDirectory() as tmp:
        mgr = launch.start_manager(instance, Path(tmp) / "rt", Path(tmp) / "log")
        try:
            script = (f"addpath('{REPO / 'build' / 'release' / 'matlab'}'); "
                      f"addpath('{Path(__file__).parent}'); bench_octave({calls}, {seconds});")
            done = subprocess.run([octave, "--no-gui", "--norc", "--quiet", "--eval", script],
                                  env={**mgr.env, "LN_MANAGER": mgr.address},
                                  capture_output=True, text=True, timeout=600)
        finally:
            mgr.stop()
    if done.returncode != 0:
        sys.exit(f"bench_octave: octave failed:\n{done.stdout}{done.stderr}")
    result: dict[str, float] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def table(r: dict[str, float]) -> str:
    rows = [("plain Octave function call (baseline)", f"{r['baseline_us']:.2f} µs"),
            ("anonymous function call", f"{r['anonymous_us']:.2f} µs"),
            ("p.write(64 B sample)", f"{r['write_us']:.2f} µs"),
            ("s.read(0) of a 64 B sample", f"{r['read_us']:.2f} µs"),
            ("write + read per call", f"{r['write_read_us']:.2f} µs "
             f"({r['write_read_us'] / r['baseline_us']:.1f}x the baseline)"),
            ("1 kHz loop (write + read + pause)", f"{r['loop_hz']:.0f} Hz achieved")]
    lines = ["| measure | value |", "| --- | --- |"] + [f"| {a} | {b} |" for a, b in rows]
    return "\n".join(lines) + f"\n\n{int(r['calls'])} calls each; loop over " \
        f"{r['loop_seconds']:g} s.\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer calls, a 1 s loop")
    args = parser.parse_args()
    result = run(2000, 1.0) if args.quick else run(20000, 5.0)
    result["quick"] = args.quick
    text = "# MATLAB/Octave client: cost per call\n\n" + table(result)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "matlab.md").write_text(text)
    (RESULTS / "matlab.json").write_text(json.dumps(result, indent=2) + "\n")
    print(text)


if __name__ == "__main__":
    main()
