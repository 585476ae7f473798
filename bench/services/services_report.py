"""Numbers and text of the service benchmark: round-trip statistics of one run, medians over
rounds, the tables and the goals with their ratios and PASS/MISS.  Pure functions over the
records that bench_services.py collects."""

from __future__ import annotations

import statistics
from pathlib import Path
from typing import Any

import numpy as np

Record = dict[str, Any]

SYSTEMS = {"raw": "raw Unix echo (C)", "ln_c": "ln C", "ln_py": "ln Python",
           "zmq": "pyzmq REQ/REP"}
FIELDS = ("p50_us", "p99_us", "mean_us", "calls_per_s")  # summarized as medians over rounds
PLACEMENTS = ("sched", "pinned")  # the placements the goals are judged on


def round_trip_stats(path: Path) -> Record:
    """Round-trip percentiles in µs and calls per second (count / sum of round trips: the
    calls run back to back) from raw uint64 ns round trips."""
    rtt = np.fromfile(path, dtype="<u8").astype(np.float64) / 1e3
    if rtt.size == 0:
        raise ValueError(f"{path}: no samples")
    p50, p99, p999 = np.percentile(rtt, [50, 99, 99.9])
    return {"n": int(rtt.size), "p50_us": float(p50), "p99_us": float(p99),
            "p999_us": float(p999), "max_us": float(rtt.max()), "mean_us": float(rtt.mean()),
            "calls_per_s": float(rtt.size / rtt.sum() * 1e6)}


def summarize(runs: list[Record]) -> list[Record]:
    """One record per (system, placement): the median of each field over the rounds that
    worked, the range of p50 and of the share on one CPU, and how many rounds failed."""
    out = []
    keys = dict.fromkeys((r["system"], r["placement"]) for r in runs)
    for system, placement in keys:
        mine = [r for r in runs if r["system"] == system and r["placement"] == placement]
        good = [r for r in mine if "error" not in r]
        rec: Record = {"system": system, "placement": placement, "rounds": len(good),
                       "failed": len(mine) - len(good)}
        if good:
            rec.update({f: statistics.median(r[f] for r in good) for f in FIELDS})
            rec["p50_min_us"] = min(r["p50_us"] for r in good)
            rec["p50_max_us"] = max(r["p50_us"] for r in good)
            shares = [r["same_cpu"] for r in good if r.get("same_cpu") is not None]
            rec["same_cpu"] = statistics.median(shares) if shares else None
        else:
            rec["error"] = mine[-1]["error"] if mine else "not run"
        out.append(rec)
    return out


def us(value: float | None) -> str:
    if value is None:
        return "-"
    return f"{value:.2f}" if value < 10 else f"{value:.1f}" if value < 1000 else f"{value:.0f}"


def find(summary: list[Record], system: str, placement: str) -> Record | None:
    for rec in summary:
        if rec["system"] == system and rec["placement"] == placement:
            return rec
    return None


def tables(summary: list[Record], placements: dict[str, str], header: str,
           unavailable: dict[str, str]) -> list[str]:
    """One table per placement, a row per system."""
    out = [header,
           "p50 range: lowest and highest p50 of the rounds; same: share of the wall time "
           "(sampled at 50 Hz) in which both processes had last run on one CPU"]
    for placement, what in placements.items():
        out += ["", f"{placement}: {what}",
                f"{'':<20}{'p50':>8}{'p99':>8}{'mean':>8}{'calls/s':>10}"
                f"{'p50 range':>16}{'same':>6}{'rounds':>8}"]
        for system, label in SYSTEMS.items():
            if system in unavailable:
                out.append(f"{label:<20}  not available: {unavailable[system]}")
                continue
            rec = find(summary, system, placement)
            if rec is None:
                out.append(f"{label:<20}  not run")
            elif "error" in rec:
                out.append(f"{label:<20}  error: {rec['error'][:70]}")
            else:
                spread = f"{us(rec['p50_min_us'])}-{us(rec['p50_max_us'])}"
                share = "-" if rec["same_cpu"] is None else f"{rec['same_cpu']:.0%}"
                done = f"{rec['rounds']}" + (f"/{rec['rounds'] + rec['failed']}"
                                             if rec["failed"] else "")
                out.append(f"{label:<20}{us(rec['p50_us']):>8}{us(rec['p99_us']):>8}"
                           f"{us(rec['mean_us']):>8}{rec['calls_per_s']:>10,.0f}"
                           f"{spread:>16}{share:>6}{done:>8}")
    return out


def _goal(name: str, summary: list[Record], system: str, baseline: str, placement: str,
          limit: float, strict: bool, unavailable: dict[str, str]) -> Record:
    need = f"{'<' if strict else '<='} {limit:g}"
    rec, ref = find(summary, system, placement), find(summary, baseline, placement)
    missing = next((s for s in (system, baseline) if s in unavailable), None)
    if missing:
        return {"goal": name, "measured": f"{SYSTEMS[missing]} not available", "ratio": None,
                "need": need, "verdict": "n/a"}
    if not rec or not ref or "error" in rec or "error" in ref:
        return {"goal": name, "measured": "not measured", "ratio": None, "need": need,
                "verdict": "MISS"}  # measured nothing: not met
    ratio = rec["p50_us"] / ref["p50_us"]
    ok = ratio < limit if strict else ratio <= limit
    return {"goal": name, "measured": f"{rec['p50_us']:.2f} / {ref['p50_us']:.2f} µs",
            "ratio": ratio, "need": need, "verdict": "PASS" if ok else "MISS"}


def goals(summary: list[Record], placements: list[str], unavailable: dict[str, str]
          ) -> list[Record]:
    result = []
    for pl in (p for p in PLACEMENTS if p in placements):
        result.append(_goal(f"C ln p50 <= 1.5x raw Unix echo ({pl})", summary, "ln_c", "raw",
                            pl, 1.5, False, unavailable))
        result.append(_goal(f"Python ln p50 < pyzmq REQ/REP ({pl})", summary, "ln_py", "zmq",
                            pl, 1.0, True, unavailable))
    return result


def goals_table(rows: list[Record]) -> list[str]:
    out = [f"{'goal':<40}{'measured':<30}{'ratio':>7}  {'need':<7} verdict"]
    for g in rows:
        ratio = "-" if g["ratio"] is None else f"{g['ratio']:.2f}"
        out.append(f"{g['goal']:<40}{g['measured']:<30}{ratio:>7}  {g['need']:<7} {g['verdict']}")
    return out
