"""Statistics and tables of bench/realtime: latency (round trip / 2) and loop period jitter
percentiles from the raw records the ping programs write, the goal with PASS/MISS, and the
text table written beside the JSON."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

Record = dict[str, Any]
QUANTILES = {"p50": 50.0, "p99": 99.0, "p99_9": 99.9, "p99_99": 99.99}
GOAL_RATIO = 1.2  # links_and_nodes p99.99 latency at most this times the futex floor's
TRANSPORTS = {"futex": "raw futex floor", "ln": "links_and_nodes", "iox": "iceoryx"}


def percentiles(values: np.ndarray) -> Record:
    """p50, p99, p99.9, p99.99 and max of `values` (µs)."""
    out = {k: float(v) for k, v in zip(QUANTILES, np.percentile(values, list(QUANTILES.values())),
                                         strict=True)}
    return {**out, "max": float(values.max())}


def stats(path: Path) -> Record:
    """From (round trip ns, wake-up lateness ns) pairs: one-way latency = round trip / 2,
    the period jitter |period - nominal| = |lateness[i] - lateness[i-1]|, and the wake-up
    lateness itself, all in µs."""
    raw = np.fromfile(path, dtype="<u8").reshape(-1, 2)
    if raw.shape[0] < 2:
        raise ValueError(f"{path}: fewer than 2 samples")
    late = raw[:, 1].astype(np.float64) / 1e3
    return {"n": int(raw.shape[0]),
            "latency_us": percentiles(raw[:, 0].astype(np.float64) / 2e3),
            "jitter_us": percentiles(np.abs(np.diff(late))),
            "wakeup_late_us": percentiles(late)}


def goal(records: list[Record], shape: str) -> Record:
    """links_and_nodes p99.99 latency against the floor's, in the same run and load."""
    got = {r["transport"]: r for r in records
           if r["shape"] == shape and "latency_us" in r}
    if "ln" not in got or "futex" not in got:
        return {"shape": shape, "verdict": "NOT MEASURED", "ratio": None}
    ln, floor = got["ln"]["latency_us"]["p99_99"], got["futex"]["latency_us"]["p99_99"]
    ratio = ln / floor if floor > 0 else None
    verdict = "PASS" if ratio is not None and ratio <= GOAL_RATIO else "MISS"
    return {"shape": shape, "ln_p99_99_us": ln, "floor_p99_99_us": floor, "ratio": ratio,
            "ln_max_us": got["ln"]["latency_us"]["max"],
            "floor_max_us": got["futex"]["latency_us"]["max"], "verdict": verdict}


def fmt(v: float | None) -> str:
    if v is None:
        return "-"
    return f"{v:.2f}" if v < 10 else f"{v:.1f}" if v < 1000 else f"{v:.0f}"


def table(records: list[Record]) -> list[str]:
    head = ("shape", "transport", "n", "lat p50", "p99", "p99.9", "p99.99", "max",
            "jit p50", "p99", "p99.9", "p99.99", "max", "overruns", "sched (ping/pong)")
    rows = [head]
    for r in records:
        name = TRANSPORTS[r["transport"]]
        if "error" in r:
            rows.append((r["shape"], name, "-", *["-"] * 10, "-", "ERROR: " + r["error"]))
            continue
        lat, jit = r["latency_us"], r["jitter_us"]
        ping, pong = r["ping"], r["pong"]
        sched = (f"{ping['policy']}/{ping['priority']}@{ping['cpus']} mlock {ping['mlockall']}"
                 f" / {pong['policy']}/{pong['priority']}@{pong['cpus']}")
        rows.append((r["shape"], name, str(r["n"]), *(fmt(lat[k]) for k in (*QUANTILES, "max")),
                     *(fmt(jit[k]) for k in (*QUANTILES, "max")), str(ping["overruns"]), sched))
    widths = [max(len(row[i]) for row in rows) for i in range(len(head) - 1)]
    out = ["latency = round trip / 2 (µs); jitter = |loop period - nominal| (µs); "
           "overruns: cycles that ended after the next deadline"]
    for row in rows:
        out.append("  ".join(c.rjust(w) if i >= 2 else c.ljust(w)
                             for i, (c, w) in enumerate(zip(row, widths, strict=False)))
                   + "  " + row[-1])
    return out


def goals_table(goals: list[Record]) -> list[str]:
    out = [f"goal: links_and_nodes p99.99 latency <= {GOAL_RATIO}x the raw futex floor's under "
           "the same load; max reported honestly"]
    for g in goals:
        if g["ratio"] is None:
            out.append(f"  {g['shape']}: {g['verdict']}")
            continue
        out.append(f"  {g['shape']}: ln p99.99 {fmt(g['ln_p99_99_us'])} µs, floor "
                   f"{fmt(g['floor_p99_99_us'])} µs, ratio {g['ratio']:.2f} -> {g['verdict']}"
                   f"  (max: ln {fmt(g['ln_max_us'])} µs, floor {fmt(g['floor_max_us'])} µs)")
    return out
