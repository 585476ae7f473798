"""The full-payload set of the topic benchmark (large messages as a producer uses zero-copy:
the whole sample copied into the loan, the whole borrowed sample copied out): its cases, the
medians over the repetitions, its tables and the issue's goals with PASS/MISS.  Pure
functions over the records bench_topics.py collects."""

from __future__ import annotations

import statistics
from typing import Any

from topics_report import find, goal, size_label, us

Record = dict[str, Any]

MIB = 1 << 20
SIZES = [MIB, 4 * MIB]
# one-way latency: the futex floor copies the whole payload four times per round trip (ping
# in, pong out and back in, ping out), the zero-copy cases three (ping into the loan, pong
# from its borrow into its loan, ping out of the borrow)
LATENCY = {
    "futex": "futex floor (C)",
    "floor_full": "shm ring floor (C)",
    "ln_c_full": "ln C zero-copy",
    "iox_full": "iceoryx C",
    "ln_py_full": "ln Python zero-copy",
    "iox2_full": "iceoryx2 Python",
}
ZC_THROUGHPUT = {
    "floor_full": "shm ring floor (C)",
    "ln_c_full": "ln C zero-copy",
    "iox_full": "iceoryx C",
    "ln_py_full": "ln Python zero-copy",
    "iox2_full": "iceoryx2 Python",
}
PLACEMENTS = ("sched", "pinned")
FLOOR_LIMIT = 1.1  # C 4 MiB p50 against the futex floor


def _median(values: list[float]) -> float | None:
    return statistics.median(values) if values else None


def latency_medians(records: list[Record]) -> list[Record]:
    """One record per size, transport and placement: medians of p50 and p99 over the
    repetitions, the lowest and highest p50, the highest max."""
    out = []
    groups: dict[tuple[int, str, str], list[Record]] = {}
    for rec in records:
        groups.setdefault((rec["size"], rec["transport"], rec["placement"]), []).append(rec)
    for (size, key, placement), recs in groups.items():
        ok = [r for r in recs if "error" not in r]
        med: Record = {
            "size": size,
            "transport": key,
            "placement": placement,
            "reps": len(ok),
            "errors": [r["error"] for r in recs if "error" in r],
        }
        if ok:
            p50s = [r["p50_us"] for r in ok]
            shares = [r["same_cpu"] for r in ok if r.get("same_cpu") is not None]
            med.update(
                p50_us=_median(p50s),
                p50_min_us=min(p50s),
                p50_max_us=max(p50s),
                p99_us=_median([r["p99_us"] for r in ok]),
                max_us=max(r["max_us"] for r in ok),
                same_cpu=_median(shares),
                n=ok[0]["n"],
                warmup=ok[0]["warmup"],
            )
        else:
            med["error"] = med["errors"][0]
        out.append(med)
    return out


def zc_medians(records: list[Record]) -> list[Record]:
    """One record per size and transport: median received msg/s over the repetitions, the
    lowest and highest, and the samples lost or overrun in all of them."""
    out = []
    groups: dict[tuple[int, str], list[Record]] = {}
    for rec in records:
        groups.setdefault((rec["size"], rec["transport"]), []).append(rec)
    for (size, key), recs in groups.items():
        ok = [r for r in recs if "error" not in r]
        med: Record = {
            "size": size,
            "transport": key,
            "reps": len(ok),
            "errors": [r["error"] for r in recs if "error" in r],
        }
        if ok:
            rates = [r["recv_rate"] for r in ok]
            rate = _median(rates) or 0.0
            med.update(
                recv_rate=rate,
                rate_min=min(rates),
                rate_max=max(rates),
                gb_per_s=rate * size / 1e9,
                buffers=ok[0]["buffers"],
                received=sum(r["received"] for r in ok),
                lost=sum(r["lost"] for r in ok),
                overruns=sum(r["overruns"] for r in ok),
            )
        else:
            med["error"] = med["errors"][0]
        out.append(med)
    return out


def latency_table(medians: list[Record], placements: dict[str, str], reps: int) -> list[str]:
    groups = [p for p in placements if any(r["placement"] == p for r in medians)]
    out = [
        f"full payload, one-way latency = round trip / 2 in µs, median of {reps} "
        "repetition(s) (p50 lo-hi: lowest and highest p50); "
        + "; ".join(f"{p}: {placements[p]}" for p in groups),
        "every sample written whole: ping copies its buffer into the loan, the echo copies "
        "the borrowed sample into its loan, ping copies the reply out",
    ]
    for size in SIZES:
        first = next((r for r in medians if r["size"] == size and "n" in r), None)
        counts = f": {first['n']:,} round trips after {first['warmup']:,} warm-up" if first else ""
        heads = [
            "     p50      p50 lo-hi     p99     max" + ("  same" if p == "sched" else "")
            for p in groups
        ]
        out += [
            "",
            size_label(size) + counts,
            f"{'':<22}" + " |".join(f"{p:^{len(h)}}" for p, h in zip(groups, heads, strict=True)),
            f"{'':<22}" + " |".join(heads),
        ]
        for key, label in LATENCY.items():
            cells = []
            for placement in groups:
                rec = find(medians, size=size, transport=key, placement=placement)
                if rec is None:
                    cell = f"{'-':>8}{'-':>15}{'-':>8}{'-':>8}"
                else:
                    span = f"{us(rec['p50_min_us'])}-{us(rec['p50_max_us'])}"
                    cell = (
                        f"{us(rec['p50_us']):>8}{span:>15}{us(rec['p99_us']):>8}"
                        f"{us(rec['max_us']):>8}"
                    )
                if placement == "sched":
                    share = rec.get("same_cpu") if rec else None
                    cell += "     -" if share is None else f"{share:>6.0%}"
                cells.append(cell)
            out.append(f"{label:<22}" + " |".join(cells))
    return out


def zc_table(medians: list[Record], reps: int, seconds: float) -> list[str]:
    out = [
        f"full payload, zero-copy throughput (queued, lossless: the publisher waits for the "
        f"subscriber's queue), {seconds:g} s per case, median of {reps} repetition(s):",
        "the publisher copies a whole source buffer into each loan; the subscriber copies "
        "each borrowed sample out whole before releasing it",
        f"{'':<22}{'size':>8}{'queue':>6}{'recv msg/s':>12}{'lo-hi':>18}{'GB/s':>7}"
        f"{'lost':>7}{'overrun':>8}",
    ]
    for size in SIZES:
        for key, label in ZC_THROUGHPUT.items():
            rec = next((r for r in medians if r["size"] == size and r["transport"] == key), None)
            if rec is None:
                continue
            if "error" in rec:
                out.append(f"{label:<22}{size_label(size):>8}  error: {rec['error'][:70]}")
                continue
            span = f"{rec['rate_min']:,.0f}-{rec['rate_max']:,.0f}"
            out.append(
                f"{label:<22}{size_label(size):>8}{rec['buffers']:>6}"
                f"{rec['recv_rate']:>12,.0f}{span:>18}{rec['gb_per_s']:>7.2f}"
                f"{rec['lost']:>7}{rec['overruns']:>8}"
            )
    return out


def _p50_goal(name: str, medians: list[Record], a: Record, b: Record, limit: float) -> Record:
    ra, rb = find(medians, **a), find(medians, **b)
    if not ra or not rb:
        return goal(name, "not measured", None, limit, True)
    return goal(
        name,
        f"{ra['p50_us']:.1f} / {rb['p50_us']:.1f} µs",
        ra["p50_us"] / rb["p50_us"],
        limit,
        True,
    )


def _throughput_goal(size: int, zc: list[Record]) -> Record:
    name = f"Py full {size_label(size)} msg/s >= iox2, lossless"
    ln, iox2 = (
        find(zc, size=size, transport="ln_py_full"),
        find(zc, size=size, transport="iox2_full"),
    )
    if not ln or not iox2 or not iox2["recv_rate"]:
        return goal(name, "not measured", None, 1.0, False)
    if ln["lost"] or ln["overruns"]:  # lossless is part of the goal
        return goal(name, f"lost {ln['lost']}, overran {ln['overruns']}", None, 1.0, False)
    return goal(
        name,
        f"{ln['recv_rate']:,.0f} / {iox2['recv_rate']:,.0f} msg/s",
        ln["recv_rate"] / iox2["recv_rate"],
        1.0,
        False,
    )


def goals(lat: list[Record], zc: list[Record], placements: list[str]) -> list[Record]:
    """The issue's goals: C zero-copy 4 MiB full-payload p50 <= 1.1x the futex floor and
    <= iceoryx, 1 MiB <= iceoryx; Python full-payload throughput at 1 and 4 MiB >= iceoryx2
    (lossless) and latency <= iceoryx2.  On medians; not measured is MISS."""
    result = []
    for pl in (p for p in PLACEMENTS if p in placements):

        def at(size: int, key: str, pl: str = pl) -> Record:
            return {"size": size, "transport": key, "placement": pl}

        result.append(
            _p50_goal(
                f"C full 4 MiB p50 <= {FLOOR_LIMIT:g}x futex ({pl})",
                lat,
                at(4 * MIB, "ln_c_full"),
                at(4 * MIB, "futex"),
                FLOOR_LIMIT,
            )
        )
        for size in (4 * MIB, MIB):
            result.append(
                _p50_goal(
                    f"C full {size_label(size)} p50 <= iceoryx ({pl})",
                    lat,
                    at(size, "ln_c_full"),
                    at(size, "iox_full"),
                    1.0,
                )
            )
        for size in SIZES:
            result.append(
                _p50_goal(
                    f"Py full {size_label(size)} p50 <= iceoryx2 ({pl})",
                    lat,
                    at(size, "ln_py_full"),
                    at(size, "iox2_full"),
                    1.0,
                )
            )
    result += [_throughput_goal(size, zc) for size in SIZES]
    return result
