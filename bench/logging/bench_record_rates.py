"""Recording at real rates: ln_record keeps up with many topics without losing a sample.

Goal (issue: recordings the ecosystem can open): 50 topics x 1 kHz x 1 KiB recorded for
60 s in the `ros2` encoding (what viewers decode) with zero lost samples.  The baseline in
the same run is the same load recorded in the `ln` encoding (raw bytes, no conversion), so
the table shows what the CDR conversion costs the recorder (CPU seconds per second).

bench_record_pub (built by scons into build/release/bench/logging/) publishes the topics,
every sample written in full (lnbench/record_1k: a counter, a frame name, joint vectors);
it starts only once ln_record has subscribed every topic.  After it stops, ln_record gets
SIGINT (it drains its queues), and the files are read back: a sample is lost unless its
topic's counter is in the file; the counters must be exactly 0..N-1 per topic.  Prints a
table and writes bench/results/record_rates.json; exits 0 whether the goal is met or not.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import signal
import subprocess
import sys
import tempfile
import time
import uuid
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "python"))  # measure this checkout, not an installed one

from links_and_nodes.manager.frontends.launch import segments, start_manager  # noqa: E402
from links_and_nodes.mcap_format import McapReader  # noqa: E402
from links_and_nodes.record.encodings import ln_decoder  # noqa: E402

PUBLISHER = REPO / "build" / "release" / "bench" / "logging" / "bench_record_pub"
MD_DIR = REPO / "bench" / "md"
GOAL = "ros2 encoding: 50 topics x 1 kHz x 1 KiB for 60 s with zero lost samples"


def log(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def encodings_offered() -> list[str]:
    """The encodings this ln_record takes (`ln` only before --encoding existed)."""
    help_text = subprocess.run([sys.executable, "-m", "links_and_nodes.record.record_cli",
                                "--help"], capture_output=True, text=True).stdout
    return ["ln", "ros2", "json"] if "--encoding" in help_text else ["ln"]


def read_back(out: Path, prefix: str) -> tuple[dict[str, int], int]:
    """Samples per topic in the files, and how many counters were out of sequence."""
    counts: dict[str, int] = {}
    expected: dict[str, int] = {}
    bad = 0
    for path in sorted(out.glob("*.mcap")):
        reader = McapReader(path, allow_truncated=True)
        decode = {name: ln_decoder(info, [str(MD_DIR)])
                  for name, info in reader.topics().items()}
        for sample in reader:
            if not sample.topic.startswith(prefix):
                continue
            counter = int.from_bytes(decode[sample.topic](sample.data)[:8], "little")
            want = expected.get(sample.topic, 0)
            bad += counter != want
            expected[sample.topic] = counter + 1
            counts[sample.topic] = counts.get(sample.topic, 0) + 1
    return counts, bad


def one_run(env: dict[str, str], tmp: Path, encoding: str, topics: int, hz: float,
            seconds: float) -> dict[str, Any]:
    prefix = f"rate{encoding}{uuid.uuid4().hex[:4]}"
    out = tmp / prefix
    pub = subprocess.Popen([str(PUBLISHER), prefix, str(topics), "2"], stdin=subprocess.PIPE,
                           stdout=subprocess.PIPE, text=True, env=env)
    assert pub.stdin is not None and pub.stdout is not None
    if pub.stdout.readline().strip() != "ready":
        raise RuntimeError("bench_record_pub did not start")
    args = [sys.executable, "-m", "links_and_nodes.record.record_cli", "-o", str(out),
            "--md-dir", str(MD_DIR), "--poll", "0.2", "--regex", re.escape(prefix) + r"\..*"]
    if encoding != "ln" or "ros2" in encodings_offered():
        args += ["--encoding", encoding]
    err_path = tmp / f"{prefix}.log"
    with open(err_path, "w") as err:
        rec = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=err, env=env)
    try:
        if pub.stdout.readline().strip() != "subscribed":
            raise RuntimeError("bench_record_pub: no subscribers")
        started = time.monotonic()
        pub.stdin.write(f"go {hz} {seconds}\n")
        pub.stdin.flush()
        result = json.loads(pub.stdout.readline())
        rec.send_signal(signal.SIGINT)
        _, status, usage = os.wait4(rec.pid, 0)
        rec.returncode = os.waitstatus_to_exitcode(status)
        wall = time.monotonic() - started
    finally:
        pub.stdin.write("quit\n")
        pub.stdin.close()
        pub.wait(30)
        if rec.poll() is None:
            rec.kill()
            rec.wait()
    counts, out_of_sequence = read_back(out, prefix)
    published = result["published_per_topic"] * topics
    recorded = sum(counts.values())
    summary = err_path.read_text()
    dropped = re.search(r"(\d+) dropped", summary)
    return {"encoding": encoding, "topics": topics, "hz": hz, "seconds": seconds,
            "published": published, "recorded": recorded, "lost": published - recorded,
            "ln_record_dropped": int(dropped.group(1)) if dropped else None,
            "out_of_sequence": out_of_sequence, "late_periods": result["late_periods"],
            "record_exit": rec.returncode,
            "record_cpu_s": usage.ru_utime + usage.ru_stime, "wall_s": wall,
            "record_cpu_share": (usage.ru_utime + usage.ru_stime) / wall,
            "bytes": sum(p.stat().st_size for p in out.glob("*.mcap"))}


def print_report(result: dict[str, Any]) -> None:
    print(f"goal: {GOAL}")
    print(f"{'encoding':<9} {'published':>10} {'recorded':>10} {'lost':>6} {'late':>5} "
          f"{'CPU s/s':>8} {'file MB':>8}  goal")
    for run in result["runs"]:
        goal = ("PASS" if run["lost"] == 0 and run["out_of_sequence"] == 0 else "MISS") \
            if run["encoding"] == "ros2" else "(baseline)"
        print(f"{run['encoding']:<9} {run['published']:>10} {run['recorded']:>10} "
              f"{run['lost']:>6} {run['late_periods']:>5} {run['record_cpu_share']:>8.2f} "
              f"{run['bytes'] / 1e6:>8.1f}  {goal}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="5 s per encoding instead of 60")
    ap.add_argument("--topics", type=int, default=50)
    ap.add_argument("--hz", type=float, default=1000.0)
    ap.add_argument("--seconds", type=float, default=None)
    ap.add_argument("--json", type=Path, default=REPO / "bench" / "results" / "record_rates.json")
    args = ap.parse_args()
    seconds = args.seconds or (5.0 if args.quick else 60.0)
    if not os.access(PUBLISHER, os.X_OK):
        log(f"{PUBLISHER} is missing: run scons -j2 first")
        return 1
    facts = {"started": time.strftime("%Y-%m-%d %H:%M:%S"), "quick": args.quick,
             "machine": platform.machine(), "cpu_count": os.cpu_count(),
             "load_start": os.getloadavg()[0]}
    runs = []
    with tempfile.TemporaryDirectory(prefix="ln_bench_record_rates.") as tmp_dir:
        tmp = Path(tmp_dir)
        instance = f"benchrec{os.getpid()}x{uuid.uuid4().hex[:6]}"
        manager = start_manager(instance, tmp / "runtime", tmp / "manager.log",
                                "--log-level", "warning")
        try:
            for encoding in ["ln", *[e for e in encodings_offered() if e == "ros2"]]:
                log(f"recording {args.topics} topics x {args.hz:g} Hz for {seconds:g} s "
                    f"in {encoding} ...")
                runs.append(one_run(manager.env, tmp, encoding, args.topics, args.hz,
                                    seconds))
        finally:
            manager.stop()
            for name in segments(instance):
                Path("/dev/shm", name).unlink(missing_ok=True)
    facts["load_end"] = os.getloadavg()[0]
    result = {"facts": facts, "goal": GOAL, "runs": runs}
    print_report(result)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=1) + "\n")
    print(f"\nwritten to {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
