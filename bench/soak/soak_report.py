"""The soak benchmark's figures: from the /proc samples and the clients' latency windows to
the time series, the growth of memory and fds from the first window after the warm-up to the
last, the goals with PASS/MISS and the printed tables.  Knows nothing about running things."""

from __future__ import annotations

import statistics
from typing import Any

P99_RATIO = 1.5  # p99 at the end at most this times the p99 at the start
ENDS = 3  # windows at each end whose median p99 is compared: one window is mostly noise
RSS_GROWTH_KIB, RSS_GROWTH_SHARE = 2048, 0.05  # allowed: the larger of 2 MiB and 5 %
FD_GROWTH = 0  # any fd more at the end is a leak
WARMUP_SHARE = 0.1  # the first tenth of the samples (at least one) is warm-up

Record = dict[str, Any]


def progress_line(sample: Record) -> str:
    clients = sample["clients"].values()
    rss = sum(c.get("rss_kib", 0) for c in clients) / 1024

    def one(s: Record | None) -> str:
        return "gone" if s is None else f"{s['rss_kib'] / 1024:.1f} MiB/{s['fds']} fds"

    return (f"  t={sample['t']:6.0f} s  manager {one(sample['manager'])}, daemon "
            f"{one(sample['daemon'])}, {len(sample['clients'])} clients {rss:.0f} MiB/"
            f"{sum(c.get('fds', 0) for c in clients)} fds")


def growth(first: Record | None, last: Record | None) -> Record:
    """RSS and fd growth of one process between two samples, and whether it is flat."""
    if not first or not last or "rss_kib" not in first or "rss_kib" not in last:
        return {"flat": False, "note": "not sampled at both ends (exited?)"}
    d_rss, d_fds = last["rss_kib"] - first["rss_kib"], last["fds"] - first["fds"]
    allowed = max(RSS_GROWTH_KIB, RSS_GROWTH_SHARE * first["rss_kib"])
    return {"rss_first_kib": first["rss_kib"], "rss_last_kib": last["rss_kib"],
            "rss_growth_kib": d_rss, "fds_first": first["fds"], "fds_last": last["fds"],
            "fds_growth": d_fds, "flat": d_rss <= allowed and d_fds <= FD_GROWTH}


def windows(stats: dict[str, list[Record]], prefixes: tuple[str, ...], t0: float,
            t_end: float, interval: float) -> list[Record]:
    """The latency windows of the clients named `prefixes*`, merged by the time they ended
    (all clients end theirs at the same multiples of `interval` in wall-clock time) within the
    soak, t0 to t_end; `t` is seconds since t0: samples, lost, errors summed; p50 the median
    and p99/p99.9/max the largest of the clients'.  Windows shorter than 80 % of the interval
    (the first, and the last, cut short by SIGTERM) are left out."""
    buckets: dict[int, list[Record]] = {}
    for name, lines in stats.items():
        if not name.startswith(prefixes):
            continue
        for w in lines:
            if w["seconds"] >= 0.8 * interval and t0 <= w["t"] <= t_end:
                buckets.setdefault(round(w["t"] / interval), []).append(w)
    out = []
    for index in sorted(buckets):
        ws = [w for w in buckets[index] if w["n"]]
        n = sum(w["n"] for w in buckets[index])
        out.append({
            "t": round(index * interval - t0), "clients": len(buckets[index]), "n": n,
            "rate": n / interval, "lost": sum(w["lost"] for w in buckets[index]),
            "errors": sum(w["errors"] for w in buckets[index]),
            "p50_us": statistics.median(w["p50_us"] for w in ws) if ws else None,
            "p99_us": max((w["p99_us"] for w in ws), default=None),
            "p999_us": max((w["p999_us"] for w in ws), default=None),
            "max_us": max((w["max_us"] for w in ws), default=None)})
    return out


def p99_goal(series: list[Record], what: str, skip: int) -> Record:
    """The median p99 of the last ENDS windows against that of the first ENDS after the
    warm-up (`skip` windows)."""
    goal = f"{what}: p99 at the end <= {P99_RATIO:g}x at the start"
    usable = [w["p99_us"] for w in series if w["p99_us"] is not None]
    n = min(ENDS, len(usable) // 2)
    if n < 1:
        return {"goal": goal, "verdict": "n/a", "value": "too few windows"}
    start = min(skip, len(usable) - 2 * n)
    first = statistics.median(usable[start:start + n])
    last = statistics.median(usable[-n:])
    ratio = last / first if first else float("inf")
    return {"goal": goal, "windows_each_end": n, "first_p99_us": first, "last_p99_us": last,
            "ratio": ratio, "value": f"{first:.0f} -> {last:.0f} us ({ratio:.2f}x)",
            "verdict": "PASS" if ratio <= P99_RATIO else "MISS"}


def summarize(rec: Record, interval: float) -> Record:
    samples = rec["samples"]
    out: Record = {"error": rec["error"], "all_ready_s": rec.get("all_ready_s"), "goals": []}
    t0, t_end = rec.get("t0", 0.0), rec.get("t_end", float("inf"))
    out["topics"] = windows(rec.get("stats", {}), ("sub",), t0, t_end, interval)
    out["services"] = windows(rec.get("stats", {}), ("call", "lcall"), t0, t_end, interval)
    skip = max(1, int(len(samples) * WARMUP_SHARE))
    out["warmup_samples"] = skip
    if len(samples) <= skip:
        out["goals"].append({"goal": "memory and fds flat", "verdict": "n/a",
                             "value": f"only {len(samples)} samples"})
        return out
    first, last = samples[skip], samples[-1]
    out["growth_from_t"], out["growth_to_t"] = first["t"], last["t"]
    grow = {"manager": growth(first["manager"], last["manager"]),
            "daemon": growth(first["daemon"], last["daemon"])}
    clients = {pid: growth(c, last["clients"].get(pid)) for pid, c in first["clients"].items()}
    out["growth"] = grow
    out["clients"] = clients
    sampled = [g for g in clients.values() if "rss_growth_kib" in g]
    out["clients_summary"] = {
        "count_first": len(first["clients"]), "count_last": len(last["clients"]),
        "rss_total_first_kib": sum(c.get("rss_kib", 0) for c in first["clients"].values()),
        "rss_total_last_kib": sum(c.get("rss_kib", 0) for c in last["clients"].values()),
        "max_rss_growth_kib": max((g["rss_growth_kib"] for g in sampled), default=None),
        "max_fds_growth": max((g["fds_growth"] for g in sampled), default=None),
        "not_flat": sum(not g["flat"] for g in clients.values())}
    cs = out["clients_summary"]
    for name, g in grow.items():
        value = (f"RSS {g['rss_growth_kib']:+d} KiB, fds {g['fds_growth']:+d}"
                 if "rss_growth_kib" in g else g["note"])
        out["goals"].append({"goal": f"{name}: memory and fds flat", "value": value,
                             "verdict": "PASS" if g["flat"] else "MISS"})
    out["goals"].append({
        "goal": f"{len(clients)} clients: memory and fds flat",
        "value": f"max RSS {cs['max_rss_growth_kib']:+d} KiB, max fds {cs['max_fds_growth']:+d}"
                 if sampled else "none sampled",
        "verdict": "PASS" if sampled and not cs["not_flat"] else "MISS"})
    win_skip = max(1, int(len(out["topics"]) * WARMUP_SHARE))
    out["goals"].append(p99_goal(out["topics"], "topics publish -> receive", win_skip))
    out["goals"].append(p99_goal(out["services"], "service calls", win_skip))
    return out


def _us(v: float | None) -> str:
    return "-" if v is None else f"{v:.0f}"


def tables(summary: Record) -> list[list[str]]:
    out = []
    topics = {w["t"]: w for w in summary["topics"]}
    services = {w["t"]: w for w in summary["services"]}
    times = sorted(set(topics) | set(services))
    step = max(1, len(times) // 12)
    shown = times[::step] + ([times[-1]] if times and times[-1] not in times[::step] else [])
    rows = ["latency over time (windows; p50 = median, p99/max = worst of the clients; us)",
            f"{'t s':>6} {'samples/s':>10} {'p50':>6} {'p99':>7} {'max':>7} {'lost':>6} "
            f"{'calls/s':>8} {'p50':>6} {'p99':>7} {'max':>7} {'errors':>6}"]
    for t in shown:
        tw, sw = topics.get(t, {}), services.get(t, {})
        rows.append(f"{t:>6} {tw.get('rate', 0):>10.0f} {_us(tw.get('p50_us')):>6} "
                    f"{_us(tw.get('p99_us')):>7} {_us(tw.get('max_us')):>7} "
                    f"{tw.get('lost', 0):>6} {sw.get('rate', 0):>8.0f} "
                    f"{_us(sw.get('p50_us')):>6} {_us(sw.get('p99_us')):>7} "
                    f"{_us(sw.get('max_us')):>7} {sw.get('errors', 0):>6}")
    out.append(rows)
    if "growth" in summary:
        rows = [f"growth from t={summary['growth_from_t']:.0f} s to t={summary['growth_to_t']:.0f} s "
                f"(the first {summary['warmup_samples']} sample(s) are warm-up)",
                f"{'process':<10} {'RSS first':>10} {'RSS last':>10} {'growth':>10} "
                f"{'fds first':>9} {'fds last':>9}"]
        for name, g in summary["growth"].items():
            if "rss_growth_kib" in g:
                rows.append(f"{name:<10} {g['rss_first_kib']:>7} KiB {g['rss_last_kib']:>6} KiB "
                            f"{g['rss_growth_kib']:>+6} KiB {g['fds_first']:>9} "
                            f"{g['fds_last']:>9}")
        cs = summary["clients_summary"]
        rows.append(f"{'clients':<10} {cs['rss_total_first_kib']:>7} KiB "
                    f"{cs['rss_total_last_kib']:>6} KiB (sum of {cs['count_first']} -> "
                    f"{cs['count_last']}); the most any one grew: RSS "
                    f"{cs['max_rss_growth_kib']} KiB, fds {cs['max_fds_growth']}")
        out.append(rows)
    rows = [f"{'goal':<62} {'value':<34} verdict"]
    rows += [f"{g['goal']:<62} {g['value']:<34} {g['verdict']}" for g in summary["goals"]]
    out.append(rows)
    return out
