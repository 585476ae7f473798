"""What the pull benchmark and the pull loss tests compute from pull_probe's JSON (one file per
consumer): delivered ratio against the samples the publisher wrote in the window, age of
information sampled at 1 kHz, packets per second, the lag behind the publisher, RTT, and
the runs of timeouts at t_max in the consumer's event log.  All times are µs of
CLOCK_REALTIME, which every namespace of the machine shares."""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

EV_TIMEOUT = 1  # pull_probe's event kinds (ln/pull.h LN_PULL_EV_*)
GRACE_US = 300_000  # samples published this close to the end may still be on their way


@dataclass
class Window:
    """The measured interval and the publisher's schedule: seq s was published at
    t0_us + (s - 1) * period_us (pull_probe pub keeps absolute deadlines)."""

    start_us: int
    end_us: int
    t0_us: float
    period_us: float

    def published(self) -> tuple[int, int]:
        """First and last seq published in [start, end - GRACE]."""
        first = int(np.ceil((self.start_us - self.t0_us) / self.period_us)) + 1
        last = int(np.floor((self.end_us - GRACE_US - self.t0_us) / self.period_us)) + 1
        return max(first, 1), last


@dataclass
class Metrics:
    delivered: float  # share of the window's samples the consumer got
    aoi_mean_ms: float
    aoi_p99_ms: float
    pkts_per_s: float
    samples: int  # received in the whole run
    lag_max_last_half: float  # publisher seq minus newest delivered seq, worst in 2nd half
    rtt_p50_ms: float | None = None
    rtt_p99_ms: float | None = None
    rtt_lost: float | None = None  # share of RTT Interests that got no answer

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def load(path: str | Path) -> dict[str, Any]:
    return json.loads(Path(path).read_text())  # type: ignore[no-any-return]


def fit_schedule(runs: list[dict[str, Any]], period_us: float) -> float:
    """t0 of the publisher from every received (seq, publish time): the median offset."""
    offsets = [pub - (seq - 1) * period_us for run in runs for seq, pub, _ in run["samples"]]
    if not offsets:
        raise ValueError("no consumer received anything: the publisher's schedule is unknown")
    return float(np.median(offsets))


def window(runs: list[dict[str, Any]], period_us: float, warmup_s: float) -> Window:
    """The interval every consumer covered, after the warm-up."""
    start = max(r["start_us"] for r in runs) + int(warmup_s * 1e6)
    end = min(r["end_us"] for r in runs)
    if end - start < 2 * GRACE_US:
        raise ValueError(f"the window is too short: {(end - start) / 1e6:.2f} s")
    return Window(start, end, fit_schedule(runs, period_us), period_us)


def aoi_ms(run: dict[str, Any], w: Window) -> np.ndarray:
    """AoI(t) = t - publish time of the newest sample received by t, every ms of the window
    (NaN before the first sample)."""
    s = np.asarray(run["samples"], dtype=np.float64).reshape(-1, 3)
    grid = np.arange(w.start_us, w.end_us, 1000.0)
    if len(s) == 0:
        return np.full(len(grid), np.nan)
    order = np.argsort(s[:, 2], kind="stable")
    recv, newest = s[order, 2], np.maximum.accumulate(s[order, 1])
    idx = np.searchsorted(recv, grid, side="right") - 1
    out = np.full(len(grid), np.nan)
    ok = idx >= 0
    out[ok] = (grid[ok] - newest[idx[ok]]) / 1000.0
    return out


def lag(run: dict[str, Any], w: Window) -> np.ndarray:
    """Publisher's seq minus the newest delivered seq, every ms of the second half."""
    s = np.asarray(run["samples"], dtype=np.float64).reshape(-1, 3)
    grid = np.arange((w.start_us + w.end_us) / 2, w.end_us, 1000.0)
    published = np.floor((grid - w.t0_us) / w.period_us) + 1
    if len(s) == 0:
        return published
    order = np.argsort(s[:, 2], kind="stable")
    recv, newest = s[order, 2], np.maximum.accumulate(s[order, 0])
    idx = np.searchsorted(recv, grid, side="right") - 1
    have = np.where(idx >= 0, newest[np.maximum(idx, 0)], 0.0)
    return published - have  # type: ignore[no-any-return]


def lag_floors(run: dict[str, Any], w: Window, stretch_s: float = 1.0) -> list[float]:
    """The smallest lag in each `stretch_s` of the second half: a consumer that keeps up
    comes back near 0 in every stretch however long a stall was; one that falls behind for
    good has floors that grow."""
    lag_ms = lag(run, w)  # one value per ms
    n = int(stretch_s * 1000)
    return [float(lag_ms[i:i + n].min()) for i in range(0, len(lag_ms), n) if len(lag_ms[i:i + n])]


def metrics(run: dict[str, Any], w: Window, packets: float | None = None) -> Metrics:
    """`packets`: datagrams counted elsewhere (the relay, for push); otherwise the
    consumer's Interests plus the packets it received, over its run."""
    first, last = w.published()
    seqs = {int(seq) for seq, _, _ in run["samples"]}
    expected = max(last - first + 1, 1)
    got = sum(1 for s in seqs if first <= s <= last)
    a = aoi_ms(run, w)
    a = a[~np.isnan(a)]
    if packets is None:
        packets = run.get("stats", {}).get("interests", 0) + run["received_packets"]
    seconds = max((run["end_us"] - run["start_us"]) / 1e6, 1e-9)
    m = Metrics(delivered=got / expected,
                aoi_mean_ms=float(a.mean()) if len(a) else float("inf"),
                aoi_p99_ms=float(np.percentile(a, 99)) if len(a) else float("inf"),
                pkts_per_s=packets / seconds, samples=len(run["samples"]),
                lag_max_last_half=float(lag(run, w).max()))
    rtt = np.asarray(run.get("rtt_us", []), dtype=np.float64)
    if len(rtt):
        m.rtt_p50_ms = float(np.median(rtt)) / 1000
        m.rtt_p99_ms = float(np.percentile(rtt, 99)) / 1000
    if run.get("rtt_sent"):
        m.rtt_lost = 1 - len(rtt) / run["rtt_sent"]
    return m


def runs_at_t_max(run: dict[str, Any], t_max_ms: int, together_us: float = 2000,
                  since_us: float = 0) -> int:
    """The longest run of timeouts at t = t_max with no sample received in between, counted
    in rounds: timeouts that follow each other within `together_us` (pass the publish period:
    the slots of one window expire a period apart) count once, since they are one wait at
    t_max, not several; a timeout at t < t_max or a received sample ends the run.  Only
    timeouts from `since_us` on count (the window, after the start-up)."""
    marks = [(at, 0, t_ms) for at, kind, _, t_ms in run["events"]
             if kind == EV_TIMEOUT and at >= since_us]
    marks += [(recv, 1, 0) for _, _, recv in run["samples"]]
    longest = current = 0
    last_at = None
    for at, what, t_ms in sorted(marks):
        if what == 1 or t_ms < t_max_ms:
            current, last_at = 0, None
            continue
        if last_at is None or at - last_at > together_us:
            current += 1
        last_at = at
        longest = max(longest, current)
    return longest
