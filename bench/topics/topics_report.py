"""Numbers and text of the topic benchmark: percentiles from raw round trips, the latency,
throughput and publish-cost tables, and the goals with their ratios and PASS/MISS.
Pure functions over the result records that bench_topics.py collects."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

Record = dict[str, Any]

LATENCY = {"futex": "futex floor (C)", "ln_c": "ln C copy", "ln_c_zc": "ln C zero-copy",
           "floor_zc": "shm ring floor (C)", "iox": "iceoryx C", "ln_py": "ln Python",
           "zmq": "pyzmq REQ/REP"}
ZC_THROUGHPUT = {"ln_c_zc": "ln C zero-copy", "ln_py_zc": "ln Python zero-copy",
                 "floor_zc": "shm ring floor (C)", "iox": "iceoryx C",
                 "iox2": "iceoryx2 Python"}
FAULTS_LIMIT = 0.01  # minor faults per sample that still count as none (a stray few per run)
THROUGHPUT = {("ln_c", "nowait"): "ln C, no wait", ("ln_c", "wait"): "ln C, wait for subs",
              ("ln_py", "nowait"): "ln Python, no wait",
              ("ln_py", "wait"): "ln Python, wait for subs",
              ("zmq", "push"): "pyzmq PUSH/PULL", ("zmq", "pub"): "pyzmq PUB/SUB"}
PUB_COST = {"memcpy": "memcpy into a plain buffer", "write_no_subscriber": "ln_write, no subscriber",
            "loan_no_subscriber": "ln_write_loan + commit, no subscriber",
            "write_idle_subscriber": "ln_write, subscriber not waiting"}
PLACEMENTS = ("sched", "pinned")  # the placements the goals are judged on


def size_label(size: int) -> str:
    for unit, scale in (("MiB", 1 << 20), ("KiB", 1 << 10)):
        if size >= scale and size % scale == 0:
            return f"{size // scale} {unit}"
    return f"{size} B"


def one_way_stats(path: Path) -> Record:
    """One-way latency (round trip / 2) percentiles in µs from raw uint64 ns round trips."""
    rtt = np.fromfile(path, dtype="<u8").astype(np.float64) / 2e3
    if rtt.size == 0:
        raise ValueError(f"{path}: no samples")
    p50, p99, p999 = np.percentile(rtt, [50, 99, 99.9])
    return {"n": int(rtt.size), "p50_us": float(p50), "p99_us": float(p99),
            "p999_us": float(p999), "max_us": float(rtt.max()), "mean_us": float(rtt.mean())}


def us(value: float | None) -> str:
    if value is None:
        return "-"
    return f"{value:.2f}" if value < 10 else f"{value:.1f}" if value < 1000 else f"{value:.0f}"


def find(records: list[Record], **key: Any) -> Record | None:
    for rec in records:
        if all(rec.get(k) == v for k, v in key.items()) and "error" not in rec:
            return rec
    return None


def latency_tables(records: list[Record], sizes: list[int],
                   placements: dict[str, str]) -> list[str]:
    """One table per size: a row per transport, a column group per placement measured."""
    fields = ("p50_us", "p99_us", "p999_us", "max_us")
    out = ["one-way latency = round trip / 2, in µs; "
           + "; ".join(f"{k}: {v}" for k, v in placements.items()),
           "same: share of the wall time (sampled at 50 Hz) in which both processes had last run "
           "on one CPU; fast round trips take little time, so a low share can go with a low p50"]
    for size in sizes:
        groups = [p for p in placements if any(
            r["size"] == size and r["placement"] == p for r in records)]
        first = next((r for r in records if r["size"] == size and "n" in r), None)
        counts = f": {first['n']:,} round trips after {first['warmup']:,} warm-up" if first else ""
        heads = ["     p50     p99   p99.9     max" + (" same" if p == "sched" else "")
                 for p in groups]
        out += ["", size_label(size) + counts,
                f"{'':<18}" + " |".join(f"{p:^{len(h)}}" for p, h in zip(groups, heads,
                                                                          strict=True)),
                f"{'':<18}" + " |".join(heads)]
        for key, label in LATENCY.items():
            cells = []
            for placement in groups:
                rec = find(records, size=size, transport=key, placement=placement)
                cell = "".join(f"{us(rec[f] if rec else None):>8}" for f in fields)
                if placement == "sched":
                    share = rec.get("same_cpu") if rec else None
                    cell += "    -" if share is None else f"{share:>5.0%}"
                cells.append(cell)
            out.append(f"{label:<18}" + " |".join(cells))
    return out


def throughput_table(records: list[Record]) -> list[str]:
    out = [f"{'throughput':<26}{'size':>8}{'sent':>10}{'received':>10}{'lost':>9}"
           f"{'recv msg/s':>12}{'GB/s':>8}{'send msg/s':>12}"]
    for rec in records:
        label = THROUGHPUT[(rec["transport"], rec["mode"])]
        if "error" in rec:
            out.append(f"{label:<26}{size_label(rec['size']):>8}  error: {rec['error'][:60]}")
            continue
        out.append(f"{label:<26}{size_label(rec['size']):>8}{rec['sent']:>10}"
                   f"{rec['received']:>10}{rec['lost']:>9}{rec['recv_rate']:>12,.0f}"
                   f"{rec['gb_per_s']:>8.2f}{rec['send_rate']:>12,.0f}")
    return out


def zc_throughput_table(records: list[Record]) -> list[str]:
    out = ["zero-copy throughput: loan, write the first and last 8 bytes, commit; borrow, read "
           "them, release;",
           "the publisher waits for a full queue (no loss by design), each case runs a fixed "
           "time; GB/s = samples/s x size",
           "(what the zero-copy path makes available, not bytes copied); faults: minor page "
           "faults per sample after two laps of the ring",
           f"{'':<22}{'size':>8}{'queue':>6}{'received':>10}{'lost':>7}{'recv msg/s':>13}"
           f"{'GB/s':>9}{'pub flt':>9}{'sub flt':>9}"]
    for rec in records:
        label = ZC_THROUGHPUT[rec["transport"]]
        if "error" in rec:
            out.append(f"{label:<22}{size_label(rec['size']):>8}  error: {rec['error'][:70]}")
            continue
        out.append(f"{label:<22}{size_label(rec['size']):>8}{rec['buffers']:>6}"
                   f"{rec['received']:>10}{rec['lost']:>7}{rec['recv_rate']:>13,.0f}"
                   f"{rec['gb_per_s']:>9.1f}{_flt(rec.get('pub_minflt_per_sample')):>9}"
                   f"{_flt(rec.get('sub_minflt_per_sample')):>9}")
    return out


def _flt(value: float | None) -> str:
    return "-" if value is None else f"{value:.3f}" if value < 100 else f"{value:.0f}"


def faults_table(lat: list[Record], zc: list[Record]) -> list[str]:
    """Minor page faults per sample of both sides of every latency case that counts them."""
    keys = [k for k in LATENCY if any(r["transport"] == k and "ping_minflt" in r for r in lat)]
    sizes = sorted({r["size"] for r in lat})
    out = ["minor page faults per round trip after the warm-up (getrusage), ping / pong, the "
           "scheduler's placement",
           f"{'':<20}" + "".join(f"{size_label(s):>15}" for s in sizes)]
    for key in keys:
        cells = []
        for size in sizes:
            rec = find(lat, size=size, transport=key, placement="sched")
            cells.append("-" if not rec or "ping_minflt" not in rec else
                         f"{_flt(rec['ping_minflt_per_sample'])}/"
                         f"{_flt(rec['pong_minflt_per_sample'])}")
        out.append(f"{LATENCY[key]:<20}" + "".join(f"{c:>15}" for c in cells))
    worst = worst_faults(lat, zc)
    out.append(f"worst ln case: {_flt(worst[0])} per sample ({worst[1]})" if worst[1] else
               "worst ln case: not measured")
    return out


def summary_table(lat: list[Record], zc: list[Record], zc_sizes: list[int]) -> list[str]:
    """Large messages at a glance: p50 one way (sched) and zero-copy throughput by size."""
    sizes = sorted({*zc_sizes, *(r["size"] for r in lat if r["size"] >= 1 << 20)})
    out = ["large messages at a glance (the scheduler's placement): one-way p50 µs; "
           "zero-copy msg/s (GB/s)",
           f"{'':<28}" + "".join(f"{size_label(s):>17}" for s in sizes)]
    for key in ("ln_c", "ln_c_zc", "floor_zc", "iox"):
        cells = []
        for size in sizes:
            rec = find(lat, size=size, transport=key, placement="sched")
            cells.append(us(rec["p50_us"]) if rec else "-")
        out.append(f"{'p50 ' + LATENCY[key]:<28}" + "".join(f"{c:>17}" for c in cells))
    for key, label in ZC_THROUGHPUT.items():
        cells = []
        for size in sizes:
            rec = find(zc, size=size, transport=key)
            cells.append(f"{rec['recv_rate']:,.0f} ({rec['gb_per_s']:.0f})" if rec else "-")
        out.append(f"{'thr ' + label:<28}" + "".join(f"{c:>17}" for c in cells))
    return out


def worst_faults(lat: list[Record], zc: list[Record]) -> tuple[float, str]:
    """The most minor faults per sample of any side of any ln case, and which it was."""
    worst, where = 0.0, ""
    for rec in lat:
        if rec.get("transport", "").startswith("ln_") and "ping_minflt_per_sample" in rec:
            for side in ("ping", "pong"):
                value = rec[f"{side}_minflt_per_sample"]
                if value >= worst:
                    worst, where = value, (f"{LATENCY[rec['transport']]} latency "
                                           f"{size_label(rec['size'])} {rec['placement']} {side}")
    for rec in zc:
        if rec.get("transport", "").startswith("ln_") and "error" not in rec:
            for side in ("pub", "sub"):
                value = rec.get(f"{side}_minflt_per_sample")
                if value is not None and value >= worst:
                    worst, where = value, (f"{ZC_THROUGHPUT[rec['transport']]} throughput "
                                           f"{size_label(rec['size'])} {side}")
    return worst, where


def pub_cost_table(cost: Record) -> list[str]:
    if "error" in cost:
        return [f"publish cost: error: {cost['error']}"]
    rounds, count = cost["rounds"], cost["count"]
    out = [f"publish with no waiting reader, 64 B: ns per op, median of {rounds} rounds of "
           f"{count:,} (min, max)"]
    for key, label in PUB_COST.items():
        m = cost[key]
        extra = ""
        if "cycles" in m:
            extra = f"   {m['cycles']:.0f} cycles, {m['instructions']:.0f} instructions"
        out.append(f"{label:<40}{m['median_ns']:>8.1f}  ({m['min_ns']:.1f}, "
                   f"{m['max_ns']:.1f}){extra}")
    return out


def goal(name: str, measured: str, ratio: float | None, limit: float, at_most: bool) -> Record:
    if ratio is None:
        verdict = "MISS"  # not measured counts as not met
    else:
        verdict = "PASS" if (ratio <= limit if at_most else ratio >= limit) else "MISS"
    need = f"{'<=' if at_most else '>='} {limit:g}"
    return {"goal": name, "measured": measured, "ratio": ratio, "need": need, "verdict": verdict}


def _lat_ratio(records: list[Record], a: Record, b: Record) -> tuple[str, float | None]:
    ra, rb = find(records, **a), find(records, **b)
    if not ra or not rb:
        return "not measured", None
    return f"{ra['p50_us']:.2f} / {rb['p50_us']:.2f} µs", ra["p50_us"] / rb["p50_us"]


def goals(lat: list[Record], thr: list[Record], zc: list[Record], cost: Record
          ) -> list[Record]:
    result = []
    for pl in PLACEMENTS:
        text, ratio = _lat_ratio(lat, {"size": 64, "transport": "ln_c", "placement": pl},
                                 {"size": 64, "transport": "futex", "placement": pl})
        result.append(goal(f"C 64 B p50 <= 1.2x futex floor ({pl})", text, ratio, 1.2, True))
        text, ratio = _lat_ratio(lat, {"size": 4 << 20, "transport": "ln_c_zc", "placement": pl},
                                 {"size": 4 << 20, "transport": "iox", "placement": pl})
        result.append(goal(f"zero-copy 4 MiB p50 <= iceoryx ({pl})", text, ratio, 1.0, True))
        text, ratio = _lat_ratio(lat, {"size": 4 << 20, "transport": "ln_c_zc", "placement": pl},
                                 {"size": 64, "transport": "ln_c_zc", "placement": pl})
        result.append(goal(f"zero-copy 4 MiB p50 <= 1.5x 64 B ({pl})", text, ratio, 1.5, True))
        text, ratio = _lat_ratio(lat, {"size": 64, "transport": "ln_py", "placement": pl},
                                 {"size": 64, "transport": "zmq", "placement": pl})
        result.append(goal(f"Python 64 B p50 <= 0.5x pyzmq ({pl})", text, ratio, 0.5, True))
    ln_ok = [r for r in thr if r["transport"] == "ln_py" and r["size"] == 64
             and "error" not in r and r["lost"] == 0 and r["overruns"] == 0]
    zmq = [r for r in thr if r["transport"] == "zmq" and r["size"] == 64 and "error" not in r]
    text, ratio = "no zero-loss Python run" if not ln_ok else "no pyzmq run", None
    if ln_ok and zmq:
        best, ref = max(r["recv_rate"] for r in ln_ok), max(r["recv_rate"] for r in zmq)
        text, ratio = f"{best:,.0f} / {ref:,.0f} msg/s", best / ref
    result.append(goal("Python 64 B queued >= 2x pyzmq, no loss", text, ratio, 2.0, False))
    ln_zc, iox2 = find(zc, size=4 << 20, transport="ln_py_zc"), find(zc, size=4 << 20,
                                                                         transport="iox2")
    text, ratio = "not measured", None
    if ln_zc and iox2 and iox2["recv_rate"] > 0:
        text = f"{ln_zc['recv_rate']:,.0f} / {iox2['recv_rate']:,.0f} msg/s"
        ratio = ln_zc["recv_rate"] / iox2["recv_rate"]
    result.append(goal("Python zero-copy 4 MiB msg/s >= iceoryx2", text, ratio, 1.0, False))
    worst, where = worst_faults(lat, zc)
    text, ratio = ("not measured", None) if not where else (f"{worst:.3f}/sample, worst", worst)
    faults = goal(f"ln minor faults per sample <= {FAULTS_LIMIT:g}", text, ratio, FAULTS_LIMIT,
                   True)
    faults["worst_case"] = where
    result.append(faults)
    idle = cost.get("write_idle_subscriber")
    text, ratio = ("not measured", None) if not idle else (
        f"{idle['median_ns']:.1f} ns", idle["median_ns"] / 100.0)
    result.append(goal("publish, no waiting reader <= 100 ns", text, ratio, 1.0, True))
    return result


def goals_table(rows: list[Record]) -> list[str]:
    out = [f"{'goal':<44}{'measured':<28}{'ratio':>7}  {'need':<7} verdict"]
    for g in rows:
        ratio = "-" if g["ratio"] is None else f"{g['ratio']:.2f}"
        out.append(f"{g['goal']:<44}{g['measured']:<28}{ratio:>7}  {g['need']:<7} {g['verdict']}")
    return out
