"""`topic hz` / `topic bw` statistics on synthetic samples (sequence number, publish time)
whose periods the test chooses: counts, rate, mean, min, max and standard deviation of the
periods, gaps, the window, and the lines printed from them."""

from __future__ import annotations

import math
import statistics

import pytest

from links_and_nodes.tools.introspection.stats import (
    PeriodStats,
    Window,
    bandwidth,
    bw_line,
    byte_rate,
    duration,
    hz_line,
    period_stats,
)

T0 = 1_700_000_000_000_000_000  # ns, an arbitrary CLOCK_REALTIME


def samples(periods_ms: list[float], first_seq: int = 1) -> list[tuple[int, int]]:
    out = [(first_seq, T0)]
    for p in periods_ms:
        seq, t = out[-1]
        out.append((seq + 1, t + round(p * 1e6)))
    return out


def test_n_samples_make_n_minus_1_periods_with_their_statistics() -> None:
    periods = [10.0, 10.0, 12.0, 8.0, 10.0, 11.0]
    stats = period_stats(samples(periods))
    assert stats is not None
    assert (stats.samples, stats.periods, stats.missed) == (7, 6, 0)
    seconds = [p / 1e3 for p in periods]
    assert stats.mean_s == pytest.approx(statistics.fmean(seconds), abs=1e-15)
    assert stats.min_s == pytest.approx(0.008, abs=1e-15)
    assert stats.max_s == pytest.approx(0.012, abs=1e-15)
    assert stats.std_s == pytest.approx(statistics.pstdev(seconds), abs=1e-15)
    assert stats.span_s == pytest.approx(0.061, abs=1e-15)
    assert stats.rate_hz == pytest.approx(6 / 0.061)
    assert stats.rate_hz == pytest.approx(1 / stats.mean_s)  # without gaps they agree


def test_a_constant_period_has_no_spread() -> None:
    stats = period_stats(samples([1.0] * 999))
    assert stats is not None
    assert (stats.samples, stats.periods) == (1000, 999)
    assert stats.rate_hz == pytest.approx(1000.0)
    assert stats.std_s == pytest.approx(0.0, abs=1e-12)
    assert stats.min_s == stats.max_s == pytest.approx(0.001)


def test_gaps_are_no_periods_but_count_in_the_rate() -> None:
    # seq 1, 2, 3 at 10 ms, then 6 (4 and 5 not seen) 30 ms later, then 7 at 10 ms
    data = [(1, T0), (2, T0 + 10_000_000), (3, T0 + 20_000_000), (6, T0 + 50_000_000),
            (7, T0 + 60_000_000)]
    stats = period_stats(data)
    assert stats is not None
    assert (stats.samples, stats.periods, stats.missed) == (5, 3, 2)
    assert stats.max_s == pytest.approx(0.010)  # the 30 ms across the gap is no period
    assert stats.rate_hz == pytest.approx(6 / 0.060)  # 6 sequence numbers in 60 ms


def test_too_few_samples_and_no_periods() -> None:
    assert period_stats([]) is None
    assert period_stats([(5, T0)]) is None
    stats = period_stats([(1, T0), (3, T0 + 20_000_000)])
    assert stats is not None
    assert (stats.periods, stats.missed, stats.mean_s, stats.std_s) == (0, 1, None, None)
    assert stats.rate_hz == pytest.approx(100.0)
    same_time = period_stats([(1, T0), (2, T0)])
    assert same_time is not None and same_time.rate_hz == 0.0


def test_window_keeps_the_newest_and_restarts_when_numbers_go_back() -> None:
    win = Window(4)
    for seq, t in samples([10.0, 10.0, 20.0, 20.0, 20.0]):
        win.add(seq, t)
    stats = win.stats()
    assert stats is not None
    assert (stats.samples, stats.periods, win.received) == (4, 3, 6)
    assert stats.mean_s == pytest.approx(0.020)  # only the newest four samples
    win.add(1, T0 + 10**9)  # a topic made anew counts from 1 again
    assert win.stats() is None and list(win.samples) == [(1, T0 + 10**9)]
    with pytest.raises(ValueError):
        Window(1)


def test_bandwidth_is_size_times_rate() -> None:
    stats = period_stats(samples([10.0] * 10))
    assert stats is not None
    assert bandwidth(stats, 940) == pytest.approx(94_000.0)
    assert bw_line(stats, 940) == ("bandwidth: 94.00 KB/s  (940 B x 100.000 Hz)  window: "
                                   "11 samples, 10 periods, 0 missed")


def test_lines_and_units() -> None:
    stats = PeriodStats(5, 4, 0, 0.04, 100.0, 0.01, 0.0095, 0.0105, 0.00025)
    assert hz_line(stats) == ("rate: 100.000 Hz  mean: 10.000 ms  min: 9.500 ms  max: "
                              "10.500 ms  std dev: 250.0 us  window: 5 samples, 4 periods, "
                              "0 missed")
    no_periods = PeriodStats(2, 0, 1, 0.02, 100.0, None, None, None, None)
    assert "mean: -  min: -  max: -  std dev: -" in hz_line(no_periods)
    assert duration(2.5) == "2.500 s" and duration(0.0000125) == "12.5 us"
    assert [byte_rate(v) for v in (512, 1500, 2.5e6, 3e9, 4e12)] == [
        "512 B/s", "1.50 KB/s", "2.50 MB/s", "3.00 GB/s", "4000.00 GB/s"]
    assert stats.as_dict()["rate_hz"] == 100.0 and not math.isnan(stats.as_dict()["min_s"])
