"""Numbers and text of the Rust benchmark (bench_rust.py): the median over repetitions of
each case's one-way latency, the tables per placement and the goals with their ratios and
PASS/MISS.  Pure functions over the records the driver collects."""

from __future__ import annotations

import statistics
from typing import Any

Record = dict[str, Any]

TRANSPORTS = {
    "ln_c": "ln C (lat_ln)",
    "ln_rust": "ln Rust (lat_rust)",
    "iox2": "iceoryx2 (lat_iox2)",
}
MODES = {"copy": "copy", "zc": "zero-copy, first+last 8 B", "full": "zero-copy, whole sample"}
C_LIMIT = 1.1  # Rust p50 <= 1.1x C
C_SIZES = (64, 4096, 1 << 20)  # sizes of the C goal
C_MODES = ("copy", "zc")  # lat_ln's own modes; "full" is shown beside them
IOX2_SIZES = (64, 4 << 20)  # sizes of the iceoryx2 goal
JUDGED = ("os", "pinned")  # the placements the goals are judged in
IOX2_MODE = "full"  # the way users use zero-copy: the whole sample in, the whole sample out


def size_label(size: int) -> str:
    for unit, scale in (("MiB", 1 << 20), ("KiB", 1 << 10)):
        if size >= scale and size % scale == 0:
            return f"{size // scale} {unit}"
    return f"{size} B"


def us(value: float | None) -> str:
    if value is None:
        return "-"
    return f"{value:.2f}" if value < 10 else f"{value:.1f}" if value < 1000 else f"{value:.0f}"


def medians(records: list[Record]) -> dict[tuple[str, int, str, str], Record]:
    """(placement, size, mode, transport) -> median over the repetitions that worked of
    p50/p99/p99.9 and the share with both sides on one CPU, the lowest and highest p50, and
    the worst minor faults per round trip; failed repetitions are counted."""
    groups: dict[tuple[str, int, str, str], list[Record]] = {}
    for rec in records:
        key = (rec["placement"], rec["size"], rec["mode"], rec["transport"])
        groups.setdefault(key, []).append(rec)
    out: dict[tuple[str, int, str, str], Record] = {}
    for key, recs in groups.items():
        ok = [r for r in recs if "error" not in r]
        agg: Record = {"reps": len(ok), "failed": len(recs) - len(ok)}
        if not ok:
            agg["error"] = recs[-1]["error"]
        else:
            for field in ("p50_us", "p99_us", "p999_us"):
                agg[field] = statistics.median(r[field] for r in ok)
            agg["p50_min_us"] = min(r["p50_us"] for r in ok)
            agg["p50_max_us"] = max(r["p50_us"] for r in ok)
            shares = [r["same_cpu"] for r in ok if r.get("same_cpu") is not None]
            agg["same_cpu"] = statistics.median(shares) if shares else None
            agg["minflt_per_sample"] = max(
                max(r.get("ping_minflt_per_sample", 0.0), r.get("pong_minflt_per_sample", 0.0))
                for r in ok
            )
        out[key] = agg
    return out


def ratio(
    med: dict[tuple[str, int, str, str], Record],
    placement: str,
    size: int,
    mode: str,
    num: str,
    den: str,
) -> float | None:
    a, b = med.get((placement, size, mode, num)), med.get((placement, size, mode, den))
    if not a or not b or "p50_us" not in a or "p50_us" not in b or not b["p50_us"]:
        return None
    return float(a["p50_us"] / b["p50_us"])


def cell(rec: Record | None) -> str:
    if rec is None:
        return f"{'not run':>15}"
    if "p50_us" not in rec:
        return f"{'failed':>15}"
    return f"{us(rec['p50_us']):>7} {us(rec['p99_us']):>7}"


def latency_table(
    med: dict[tuple[str, int, str, str], Record],
    placement: str,
    what: str,
    sizes: list[int],
    modes: list[str],
) -> list[str]:
    """One table for a placement: a row per size and mode, p50 and p99 per transport and
    the ratios the goals use."""
    head = " | ".join(f"{t:^15}" for t in ("ln C", "ln Rust", "iceoryx2"))
    out = [
        f"placement {placement}: {what}",
        f"{'':<15}| {head} |  Rust/C Rust/iox2" + ("  same C/R/I" if placement == "os" else ""),
        f"{'size':<8}{'mode':<7}| "
        + " | ".join(f"{'p50':>7} {'p99':>7}" for _ in TRANSPORTS)
        + " |   (p50)    (p50)",
    ]
    for size in sizes:
        for mode in modes:
            recs = [med.get((placement, size, mode, t)) for t in TRANSPORTS]
            rc = ratio(med, placement, size, mode, "ln_rust", "ln_c")
            ri = ratio(med, placement, size, mode, "ln_rust", "iox2")
            tail = "  " + "/".join(share(r) for r in recs) if placement == "os" else ""
            out.append(
                f"{size_label(size):<8}{mode:<7}| "
                + " | ".join(cell(r) for r in recs)
                + f" | {fmt_ratio(rc):>7} {fmt_ratio(ri):>8}"
                + tail
            )
    return out


def share(rec: Record | None) -> str:
    """The median share of the time both sides were on one CPU, in percent."""
    same = rec.get("same_cpu") if rec else None
    return "-" if same is None else f"{same * 100:.0f}"


def fmt_ratio(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}x"


def goals(med: dict[tuple[str, int, str, str], Record], placements: list[str]) -> list[Record]:
    """The goals, each judged in every placement: Rust p50 <= 1.1x C (64 B, 4 KiB, 1 MiB;
    copy and zc), and Rust zero-copy of the whole sample ahead of iceoryx2 (64 B, 4 MiB)."""
    out: list[Record] = []
    for size in C_SIZES:
        for mode in C_MODES:
            ratios = {p: ratio(med, p, size, mode, "ln_rust", "ln_c") for p in placements}
            out.append(
                {
                    "goal": f"Rust {mode} {size_label(size)} p50 <= {C_LIMIT}x C",
                    "size": size,
                    "mode": mode,
                    "ratios": ratios,
                    "pass": all(r is not None and r <= C_LIMIT for r in ratios.values()),
                }
            )
    for size in IOX2_SIZES:
        ratios = {p: ratio(med, p, size, IOX2_MODE, "ln_rust", "iox2") for p in placements}
        out.append(
            {
                "goal": f"Rust {IOX2_MODE} {size_label(size)} p50 < iceoryx2",
                "size": size,
                "mode": IOX2_MODE,
                "ratios": ratios,
                "pass": all(r is not None and r < 1.0 for r in ratios.values()),
            }
        )
    return out


def goals_table(rows: list[Record], placements: list[str]) -> list[str]:
    head = "".join(f"{p:>9}" for p in placements)
    out = [f"{'goal (ratio of p50 medians)':<40}{head}  result"]
    for row in rows:
        vals = "".join(f"{fmt_ratio(row['ratios'][p]):>9}" for p in placements)
        out.append(f"{row['goal']:<40}{vals}  {'PASS' if row['pass'] else 'MISS'}")
    return out
