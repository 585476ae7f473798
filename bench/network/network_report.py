"""Numbers and text of the network benchmark: medians over rounds of the latency and
throughput records that bench_network.py collects, the tables, and the goals with their
ratios and PASS/MISS.  Pure functions; percentiles come from bench/topics/topics_report.py."""

from __future__ import annotations

import statistics
from typing import Any

Record = dict[str, Any]

MIB = 1 << 20
SYSTEMS = {"raw_udp": "raw UDP (floor)", "raw_tcp": "raw TCP", "ln_local": "ln, one host",
           "ln_udp": "ln a->b, UDP", "ln_tcp": "ln a->b, TCP"}
LATENCY_CASES = [(64, "raw_udp"), (64, "raw_tcp"), (64, "ln_local"), (64, "ln_udp"),
                 (64, "ln_tcp"), (MIB, "raw_tcp"), (MIB, "ln_local"), (MIB, "ln_udp"),
                 (MIB, "ln_tcp")]
THROUGHPUT_CASES = [(MIB, "raw_tcp"), (MIB, "ln_local"), (MIB, "ln_udp"), (MIB, "ln_tcp")]
LAT_FIELDS = ("p50_us", "p99_us", "p999_us", "max_us")
THR_FIELDS = ("msgs_per_s", "mb_per_s", "lost")
# The goal: ln between hosts within 1.5x its transport's raw floor plus a fixed 10 µs.
GOAL_FACTOR, GOAL_ADD_US = 1.5, 10.0
GOALS = [("ln_udp", "raw_udp"), ("ln_tcp", "raw_tcp")]


def size_label(size: int) -> str:
    return "1 MiB" if size == MIB else f"{size} B"


def us(value: float | None) -> str:
    if value is None:
        return "-"
    return f"{value:.2f}" if value < 10 else f"{value:.1f}" if value < 1000 else f"{value:.0f}"


def throughput_stats(sent: Record, got: Record, size: int) -> Record:
    """Rates as received: samples after the first over the time from the first to the last."""
    received, elapsed = got["received"], got["elapsed_s"]
    rate = (received - 1) / elapsed if received > 1 and elapsed > 0 else 0.0
    return {"sent": sent["sent"], "received": received, "lost": sent["sent"] - received,
            "overruns": got.get("overruns", 0), "disorder": got.get("disorder", 0),
            "elapsed_s": elapsed, "msgs_per_s": rate, "mb_per_s": rate * size / 1e6,
            "send_s": sent["elapsed_s"]}


def summarize(runs: list[Record]) -> list[Record]:
    """One record per (kind, size, system): medians over the rounds that worked, the range
    of the main figure, how many rounds failed and the last error."""
    out = []
    keys = dict.fromkeys((r["kind"], r["size"], r["system"]) for r in runs)
    for kind, size, system in keys:
        mine = [r for r in runs if (r["kind"], r["size"], r["system"]) == (kind, size, system)]
        good = [r for r in mine if "error" not in r and "unavailable" not in r]
        rec: Record = {"kind": kind, "size": size, "system": system, "rounds": len(good),
                       "failed": sum("error" in r for r in mine)}
        main = "p50_us" if kind == "latency" else "mb_per_s"
        fields = LAT_FIELDS + ("resent",) if kind == "latency" else THR_FIELDS
        if good:
            rec.update({f: statistics.median(r[f] for r in good) for f in fields})
            rec["low"] = min(r[main] for r in good)
            rec["high"] = max(r[main] for r in good)
        elif any("unavailable" in r for r in mine):
            rec["unavailable"] = next(r["unavailable"] for r in mine if "unavailable" in r)
        else:
            rec["error"] = mine[-1]["error"] if mine else "not run"
        out.append(rec)
    return out


def find(summary: list[Record], kind: str, size: int, system: str) -> Record | None:
    for rec in summary:
        if (rec["kind"], rec["size"], rec["system"]) == (kind, size, system):
            return rec
    return None


def _status(rec: Record | None) -> str | None:
    """Why a row has no numbers, or None if it has them."""
    if rec is None:
        return "not run"
    if "unavailable" in rec:
        return f"not available yet: {rec['unavailable']}"
    if "error" in rec:
        return f"error: {rec['error'][:90]}"
    return None


def latency_tables(summary: list[Record], counts: dict[int, tuple[int, int]]) -> list[str]:
    out = ["one-way latency = round trip / 2, in µs, median over the rounds; resent: round "
           "trips that needed a resend (not counted in the figures)"]
    for size in sorted({s for s, _ in LATENCY_CASES}):
        count, warmup = counts[size]
        out += ["", f"{size_label(size)}: {count:,} round trips after {warmup:,} warm-up",
                f"{'':<22}{'p50':>8}{'p99':>8}{'p99.9':>8}{'max':>8}{'p50 range':>16}"
                f"{'resent':>8}{'rounds':>8}"]
        for system in (s for sz, s in LATENCY_CASES if sz == size):
            rec = find(summary, "latency", size, system)
            why = _status(rec)
            if why or rec is None:
                out.append(f"{SYSTEMS[system]:<22}  {why}")
                continue
            done = f"{rec['rounds']}" + (f"/{rec['rounds'] + rec['failed']}" if rec["failed"]
                                         else "")
            out.append(f"{SYSTEMS[system]:<22}" + "".join(f"{us(rec[f]):>8}" for f in LAT_FIELDS)
                       + f"{us(rec['low']) + '-' + us(rec['high']):>16}{rec['resent']:>8.0f}"
                       f"{done:>8}")
    return out


def throughput_table(summary: list[Record], count: int) -> list[str]:
    raw = find(summary, "throughput", MIB, "raw_tcp")
    raw_mb = raw["mb_per_s"] if raw and _status(raw) is None else None
    out = [f"throughput, 1 MiB samples: {count:,} sent as fast as possible, rates as received "
           "(median over the rounds); of raw: share of raw TCP's MB/s",
           f"{'':<22}{'msg/s':>9}{'MB/s':>9}{'MB/s range':>16}{'lost':>7}{'of raw':>8}"
           f"{'rounds':>8}"]
    for size, system in THROUGHPUT_CASES:
        rec = find(summary, "throughput", size, system)
        why = _status(rec)
        if why or rec is None:
            out.append(f"{SYSTEMS[system]:<22}  {why}")
            continue
        share = f"{rec['mb_per_s'] / raw_mb:.0%}" if raw_mb else "-"
        done = f"{rec['rounds']}" + (f"/{rec['rounds'] + rec['failed']}" if rec["failed"]
                                     else "")
        out.append(f"{SYSTEMS[system]:<22}{rec['msgs_per_s']:>9,.0f}{rec['mb_per_s']:>9,.0f}"
                   f"{rec['low']:>7,.0f}-{rec['high']:<8,.0f}{rec['lost']:>7.0f}{share:>8}"
                   f"{done:>8}")
    return out


def goals(summary: list[Record]) -> list[Record]:
    result = []
    for system, floor in GOALS:
        name = (f"{SYSTEMS[system]} 64 B p50 <= {GOAL_FACTOR:g}x {SYSTEMS[floor].split(' (')[0]}"
                f" + {GOAL_ADD_US:g} µs")
        rec, ref = find(summary, "latency", 64, system), find(summary, "latency", 64, floor)
        why = _status(rec) or _status(ref)
        if why:
            result.append({"goal": name, "measured": why, "limit_us": None, "ratio": None,
                           "verdict": "n/a" if "not available" in why else "MISS"})
            continue
        assert rec is not None and ref is not None
        limit = GOAL_FACTOR * ref["p50_us"] + GOAL_ADD_US
        result.append({"goal": name, "measured": f"{rec['p50_us']:.2f} µs",
                       "limit_us": limit, "ratio": rec["p50_us"] / ref["p50_us"],
                       "verdict": "PASS" if rec["p50_us"] <= limit else "MISS"})
    return result


def goals_table(rows: list[Record]) -> list[str]:
    out = [f"{'goal':<50}{'measured':<14}{'limit':>10}{'x floor':>9}  verdict"]
    for g in rows:
        if g["limit_us"] is None:
            out.append(f"{g['goal']:<50}{'-':<14}{'-':>10}{'-':>9}  {g['verdict']}: "
                       f"{g['measured']}")
            continue
        out.append(f"{g['goal']:<50}{g['measured']:<14}{g['limit_us']:>7.2f} µs"
                   f"{g['ratio']:>9.2f}  {g['verdict']}")
    return out
