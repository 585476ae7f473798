"""Numbers and text of the network benchmark: medians over rounds of the latency and
throughput records that bench_network.py collects (CPU per MB on each host included), the
tables, and the goals of issue 36 with their ratios and PASS/MISS.  Pure functions;
percentiles come from bench/topics/topics_report.py."""

from __future__ import annotations

import statistics
from typing import Any

Record = dict[str, Any]

KIB, MIB = 1 << 10, 1 << 20
LARGE = (64 * KIB, MIB, 4 * MIB)  # the sizes of "large messages" (latency and throughput)
SYSTEMS = {
    "raw_udp": "raw UDP (floor)",
    "raw_tcp": "raw TCP",
    "ln_local": "ln, one host",
    "ln_udp": "ln a->b, UDP",
    "ln_tcp": "ln a->b, TCP",
    "ln_udp_paced": "ln a->b, UDP at 0.5x raw",
    "ln_tcp_paced": "ln a->b, TCP at 0.7x raw",
}
# The paced cases publish at this share of raw TCP's msg/s of the same run and size: the
# throughput goal of their transport, so "lost 0" there means the goal rate is carried.
PACE = {"ln_udp_paced": 0.5, "ln_tcp_paced": 0.7}
TRANSPORT = {"ln_udp": "udp", "ln_tcp": "tcp", "ln_udp_paced": "udp", "ln_tcp_paced": "tcp"}
LATENCY_CASES = [(64, s) for s in ("raw_udp", "raw_tcp", "ln_local", "ln_udp", "ln_tcp")] + [
    (size, s) for size in LARGE for s in ("raw_tcp", "ln_local", "ln_udp", "ln_tcp")
]
# raw TCP first within a size: round 1 measures it before the paced cases need its rate
THROUGHPUT_CASES = [
    (size, s)
    for size in LARGE
    for s in ("raw_tcp", "ln_local", "ln_udp", "ln_tcp", "ln_udp_paced", "ln_tcp_paced")
]
LAT_FIELDS = ("p50_us", "p99_us", "p999_us", "max_us")
THR_FIELDS = (
    "sent",
    "msgs_per_s",
    "mb_per_s",
    "lost",
    "cpu_a_us_per_mb",
    "cpu_b_us_per_mb",
    "paced_msgs_per_s",
)
# The 64 B goal: ln between hosts within 1.5x its transport's raw floor plus a fixed 10 µs.
GOAL_FACTOR, GOAL_ADD_US = 1.5, 10.0
GOALS = [("ln_udp", "raw_udp"), ("ln_tcp", "raw_tcp")]
# The 1 MiB goals against raw TCP: p50 at most, MB/s at least this many times raw TCP's.
LARGE_GOALS = {"ln_tcp": {"p50": 1.3, "mb_per_s": 0.7}, "ln_udp": {"p50": 2.0, "mb_per_s": 0.5}}
CPU_GOAL = 2.0  # CPU per MB on each host at most this many times raw TCP's (paced cases)


def size_label(size: int) -> str:
    if size >= MIB and size % MIB == 0:
        return f"{size // MIB} MiB"
    if size >= KIB and size % KIB == 0:
        return f"{size // KIB} KiB"
    return f"{size} B"


def us(value: float | None) -> str:
    if value is None:
        return "-"
    return f"{value:.2f}" if value < 10 else f"{value:.1f}" if value < 1000 else f"{value:.0f}"


def cpu_per_mb(cpu_s: float | None, delivered_bytes: int) -> float | None:
    """µs of CPU per MB (10^6 bytes) delivered, or None without a CPU figure or bytes."""
    if cpu_s is None or delivered_bytes <= 0:
        return None
    return cpu_s * 1e6 / (delivered_bytes / 1e6)


def throughput_stats(
    sent: Record,
    got: Record,
    size: int,
    cpu: dict[str, float | None] | None = None,
    paced_msgs_per_s: float | None = None,
) -> Record:
    """Rates as received: samples after the first over the time from the first to the last.
    `cpu`: CPU seconds spent on host a and host b for the case ("a", "b"; None where a host
    has no part); `paced_msgs_per_s`: the rate the source published at (None: unpaced)."""
    received, elapsed = got["received"], got["elapsed_s"]
    rate = (received - 1) / elapsed if received > 1 and elapsed > 0 else 0.0
    cpu = cpu or {}
    return {
        "sent": sent["sent"],
        "received": received,
        "lost": sent["sent"] - received,
        "overruns": got.get("overruns", 0),
        "disorder": got.get("disorder", 0),
        "elapsed_s": elapsed,
        "msgs_per_s": rate,
        "mb_per_s": rate * size / 1e6,
        "send_s": sent["elapsed_s"],
        "cpu_a_s": cpu.get("a"),
        "cpu_b_s": cpu.get("b"),
        "cpu_a_us_per_mb": cpu_per_mb(cpu.get("a"), received * size),
        "cpu_b_us_per_mb": cpu_per_mb(cpu.get("b"), received * size),
        "paced_msgs_per_s": paced_msgs_per_s,
    }


def _median(values: list[Any]) -> float | None:
    """The median of the values that are there (None: a figure the system has not)."""
    there = [v for v in values if v is not None]
    return statistics.median(there) if there else None


def summarize(runs: list[Record]) -> list[Record]:
    """One record per (kind, size, system): medians over the rounds that worked, the range
    of the main figure, how many rounds failed and the last error; throughput records also
    have their CPU per MB as multiples of raw TCP's (cpu_a_x_raw, cpu_b_x_raw)."""
    out = []
    keys = dict.fromkeys((r["kind"], r["size"], r["system"]) for r in runs)
    for kind, size, system in keys:
        mine = [r for r in runs if (r["kind"], r["size"], r["system"]) == (kind, size, system)]
        good = [r for r in mine if "error" not in r and "unavailable" not in r]
        rec: Record = {
            "kind": kind,
            "size": size,
            "system": system,
            "rounds": len(good),
            "failed": sum("error" in r for r in mine),
        }
        main = "p50_us" if kind == "latency" else "mb_per_s"
        fields = LAT_FIELDS + ("resent",) if kind == "latency" else THR_FIELDS
        if good:
            rec.update({f: _median([r.get(f) for r in good]) for f in fields})
            rec["low"] = min(r[main] for r in good)
            rec["high"] = max(r[main] for r in good)
        elif any("unavailable" in r for r in mine):
            rec["unavailable"] = next(r["unavailable"] for r in mine if "unavailable" in r)
        else:
            rec["error"] = mine[-1]["error"] if mine else "not run"
        out.append(rec)
    for rec in out:  # CPU per MB as multiples of raw TCP's of the same size, host by host
        if rec["kind"] == "throughput" and _status(rec) is None:
            raw = _good(out, "throughput", rec["size"], "raw_tcp")
            rec["cpu_a_x_raw"], rec["cpu_b_x_raw"] = cpu_ratios(rec, raw)
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


def _good(summary: list[Record], kind: str, size: int, system: str) -> Record | None:
    rec = find(summary, kind, size, system)
    return rec if _status(rec) is None else None


def _rounds(rec: Record) -> str:
    return f"{rec['rounds']}" + (f"/{rec['rounds'] + rec['failed']}" if rec["failed"] else "")


def latency_tables(summary: list[Record], counts: dict[int, tuple[int, int]]) -> list[str]:
    out = [
        "one-way latency = round trip / 2, in µs, median over the rounds; resent: round "
        "trips that needed a resend (not counted in the figures)"
    ]
    for size in sorted({s for s, _ in LATENCY_CASES}):
        count, warmup = counts[size]
        out += [
            "",
            f"{size_label(size)}: {count:,} round trips after {warmup:,} warm-up",
            f"{'':<22}{'p50':>8}{'p99':>8}{'p99.9':>8}{'max':>8}{'p50 range':>16}"
            f"{'resent':>8}{'rounds':>8}",
        ]
        for system in (s for sz, s in LATENCY_CASES if sz == size):
            rec = find(summary, "latency", size, system)
            why = _status(rec)
            if why or rec is None:
                out.append(f"{SYSTEMS[system]:<22}  {why}")
                continue
            out.append(
                f"{SYSTEMS[system]:<22}"
                + "".join(f"{us(rec[f]):>8}" for f in LAT_FIELDS)
                + f"{us(rec['low']) + '-' + us(rec['high']):>16}{rec['resent']:>8.0f}"
                f"{_rounds(rec):>8}"
            )
    return out


def cpu_ratios(rec: Record, raw: Record | None) -> tuple[float | None, float | None]:
    """CPU per MB of `rec` on host a and host b as multiples of raw TCP's on the same host.
    ln on one host has its whole cost on a: that is compared with raw TCP's a + b."""

    def ratio(mine: float | None, ref: float | None) -> float | None:
        return mine / ref if mine is not None and ref else None

    if raw is None:
        return None, None
    if rec["system"] == "ln_local":
        a, b = raw.get("cpu_a_us_per_mb"), raw.get("cpu_b_us_per_mb")
        return ratio(rec.get("cpu_a_us_per_mb"), a + b if a and b else None), None
    return (
        ratio(rec.get("cpu_a_us_per_mb"), raw.get("cpu_a_us_per_mb")),
        ratio(rec.get("cpu_b_us_per_mb"), raw.get("cpu_b_us_per_mb")),
    )


def _num(value: float | None, fmt: str, width: int) -> str:
    return f"{'-' if value is None else format(value, fmt):>{width}}"


def _times(value: float | None, width: int) -> str:
    """A ratio, with fewer decimals the larger it is (the column stays narrow)."""
    fmt = ".2f" if value is None or value < 10 else ".1f" if value < 1000 else ",.0f"
    return _num(value, fmt, width)


THR_HEAD = (
    f"{'':<26}{'msg/s':>9}{'MB/s':>9}{'MB/s range':>16}{'lost':>7}{'of raw':>8}"
    f"{'cpu a µs/MB':>13}{'x raw':>8}{'cpu b µs/MB':>13}{'x raw':>8}{'rounds':>8}"
)


def throughput_tables(summary: list[Record], counts: dict[int, int]) -> list[str]:
    out = [
        "throughput: COUNT samples sent as fast as possible, or (paced rows) at 0.5x (UDP) "
        "/ 0.7x (TCP) raw TCP's msg/s of this run, the goal rates; rates as received (median "
        "over the rounds); lost: sent but not received; of raw: share of raw TCP's MB/s",
        "cpu a / cpu b: CPU time (user + system) per MB delivered on host a (the sender: "
        "its process, and for ln its ln_daemon) and host b (the receiver); x raw: against "
        "raw TCP's on the same host; ln, one host: the host's total in cpu a, against raw "
        "TCP's a + b",
    ]
    for size in sorted({s for s, _ in THROUGHPUT_CASES}):
        raw = _good(summary, "throughput", size, "raw_tcp")
        raw_mb = raw["mb_per_s"] if raw else None
        out += ["", f"{size_label(size)}: {counts[size]:,} samples", THR_HEAD]
        for system in (s for sz, s in THROUGHPUT_CASES if sz == size):
            rec = find(summary, "throughput", size, system)
            why = _status(rec)
            if why or rec is None:
                out.append(f"{SYSTEMS[system]:<26}  {why}")
                continue
            share = f"{rec['mb_per_s'] / raw_mb:.0%}" if raw_mb else "-"
            xa, xb = rec["cpu_a_x_raw"], rec["cpu_b_x_raw"]
            out.append(
                f"{SYSTEMS[system]:<26}{rec['msgs_per_s']:>9,.0f}{rec['mb_per_s']:>9,.0f}"
                f"{rec['low']:>7,.0f}-{rec['high']:<8,.0f}{rec['lost']:>7.0f}{share:>8}"
                f"{_num(rec['cpu_a_us_per_mb'], ',.0f', 13)}{_times(xa, 8)}"
                f"{_num(rec['cpu_b_us_per_mb'], ',.0f', 13)}{_times(xb, 8)}"
                f"{_rounds(rec):>8}"
            )
    return out


def _goal(
    name: str, measured: str, limit: str, ratio: float | None, ok: bool, **extra: Any
) -> Record:
    return {
        "goal": name,
        "measured": measured,
        "limit": limit,
        "ratio": ratio,
        "verdict": "PASS" if ok else "MISS",
        **extra,
    }


def _no_data(name: str, *recs: Record | None) -> Record | None:
    """The goal's row when one of its records has no numbers (n/a while not available)."""
    why = next((w for w in map(_status, recs) if w), None)
    if why is None:
        return None
    return {
        "goal": name,
        "measured": why,
        "limit": None,
        "ratio": None,
        "verdict": "n/a" if "not available" in why else "MISS",
    }


def _latency_64_goals(summary: list[Record]) -> list[Record]:
    result = []
    for system, floor in GOALS:
        name = (
            f"{SYSTEMS[system]} 64 B p50 <= {GOAL_FACTOR:g}x {SYSTEMS[floor].split(' (')[0]}"
            f" + {GOAL_ADD_US:g} µs"
        )
        rec, ref = find(summary, "latency", 64, system), find(summary, "latency", 64, floor)
        missing = _no_data(name, rec, ref)
        if missing:
            result.append({**missing, "limit_us": None})
            continue
        assert rec is not None and ref is not None
        limit = GOAL_FACTOR * ref["p50_us"] + GOAL_ADD_US
        result.append(
            _goal(
                name,
                f"{rec['p50_us']:.2f} µs",
                f"{limit:.2f} µs",
                rec["p50_us"] / ref["p50_us"],
                rec["p50_us"] <= limit,
                limit_us=limit,
            )
        )
    return result


def _against_raw(summary: list[Record], name: str, kind: str, system: str, factor: float) -> Record:
    """1 MiB of `system` against raw TCP: p50 at most (latency) or MB/s at least
    (throughput) `factor` times raw TCP's."""
    rec, ref = find(summary, kind, MIB, system), find(summary, kind, MIB, "raw_tcp")
    missing = _no_data(name, rec, ref)
    if missing:
        return missing
    assert rec is not None and ref is not None
    if kind == "latency":
        ratio = rec["p50_us"] / ref["p50_us"]
        return _goal(name, f"{us(rec['p50_us'])} µs", f"{factor:g}x", ratio, ratio <= factor)
    ratio = rec["mb_per_s"] / ref["mb_per_s"] if ref["mb_per_s"] else 0.0
    return _goal(name, f"{rec['mb_per_s']:,.0f} MB/s", f"{factor:g}x", ratio, ratio >= factor)


def _lossless(summary: list[Record], system: str) -> Record:
    """The paced case of `system` at 1 MiB: nothing lost at the goal rate; the ratio is its
    delivered MB/s over raw TCP's."""
    name = f"{SYSTEMS[system]} TCP's msg/s, 1 MiB: lost == 0"
    rec, ref = find(summary, "throughput", MIB, system), find(summary, "throughput", MIB, "raw_tcp")
    missing = _no_data(name, rec, ref)
    if missing:
        return missing
    assert rec is not None and ref is not None
    ratio = rec["mb_per_s"] / ref["mb_per_s"] if ref["mb_per_s"] else None
    return _goal(name, f"lost {rec['lost']:.0f} of {rec['sent']:.0f}", "0", ratio, rec["lost"] == 0)


def _cpu_goals(summary: list[Record], system: str) -> list[Record]:
    """CPU per MB on each host of a paced ln case (a user's queued topic at the goal rate)
    against raw TCP's on the same host."""
    rec, ref = find(summary, "throughput", MIB, system), find(summary, "throughput", MIB, "raw_tcp")
    result = []
    for host in ("a", "b"):
        name = f"{SYSTEMS[system]}, 1 MiB: cpu {host} <= {CPU_GOAL:g}x raw TCP's"
        missing = _no_data(name, rec, ref)
        if missing:
            result.append(missing)
            continue
        assert rec is not None
        ratio = rec[f"cpu_{host}_x_raw"]
        mine = _num(rec[f"cpu_{host}_us_per_mb"], ",.0f", 0).strip()
        result.append(
            _goal(
                name,
                f"{mine} µs/MB",
                f"{CPU_GOAL:g}x",
                ratio,
                ratio is not None and ratio <= CPU_GOAL,
            )
        )
    return result


def _large_goals(summary: list[Record], system: str) -> list[Record]:
    """The 1 MiB goals of ln over `system`'s transport (ln_tcp or ln_udp)."""
    label, want, paced = SYSTEMS[system], LARGE_GOALS[system], f"{system}_paced"
    return [
        _against_raw(
            summary,
            f"{label} 1 MiB p50 <= {want['p50']:g}x raw TCP",
            "latency",
            system,
            want["p50"],
        ),
        # Delivered at the goal rate: published as fast as possible, the samples outrun the
        # link, are dropped at the sender and what arrives says more about the burst than
        # about the rate the stream carries (that row stays in the table as the ceiling).
        _against_raw(
            summary,
            f"{label} 1 MiB MB/s delivered at the goal rate >= {want['mb_per_s']:g}x raw TCP",
            "throughput",
            paced,
            want["mb_per_s"],
        ),
        # Only TCP promises every sample (UDP: the newest).
        *([_lossless(summary, paced)] if system == "ln_tcp" else []),
        *_cpu_goals(summary, paced),
    ]


def goals(summary: list[Record]) -> list[Record]:
    """Every goal: 64 B latency against the transport's floor, then the large message goals
    of issue 36 (1 MiB against raw TCP of the same run): latency, throughput delivered at the
    goal rate, no loss there (TCP), CPU per MB on each host."""
    return (
        _latency_64_goals(summary)
        + _large_goals(summary, "ln_tcp")
        + _large_goals(summary, "ln_udp")
    )


def goals_table(rows: list[Record]) -> list[str]:
    out = [
        f"{'goal':<58}{'measured':<20}{'limit':>10}{'ratio':>8}  verdict",
        "(ratio: the measured figure over its reference: the raw floor, raw TCP's p50, "
        "MB/s or CPU per MB)",
    ]
    for g in rows:
        if g["limit"] is None:
            out.append(
                f"{g['goal']:<58}{'-':<20}{'-':>10}{'-':>8}  {g['verdict']}: {g['measured']}"
            )
            continue
        out.append(
            f"{g['goal']:<58}{g['measured']:<20}{g['limit']:>10}"
            f"{_times(g['ratio'], 8)}  {g['verdict']}"
        )
    return out
