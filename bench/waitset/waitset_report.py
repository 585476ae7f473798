"""Numbers and tables of the waitset benchmark: percentiles of the one-way latencies each
subscriber wrote, CPU time per wait, the idle processes' share of a CPU, and the goals of
issue 29 with PASS/MISS.  Knows nothing about processes; bench_waitset.py runs them."""

from __future__ import annotations

import statistics
from array import array
from pathlib import Path
from typing import Any

Record = dict[str, Any]

RATIO = 1.2  # waitset p50 against the blocking read's; N = 1000 against N = 1
IDLE_LIMIT = 0.001  # share of one CPU (0.1 %)
SCALING = (1, 10, 100, 1000)
# case -> (label, language); the order of the table
CASES: dict[str, tuple[str, str]] = {
    "read": ("C ln_read, blocking (default spin 20 µs)", "c"),
    "read0": ("C ln_read, blocking, spin_us 0 (reference)", "c"),
    **{f"waitset{n}": ("C waitset", "c") for n in SCALING},
    "py_read": ("Python sub.read(), blocking", "py"),
    "py_async": ("Python await sub.read_async(), asyncio", "py"),
}


def read_latencies(path: Path) -> list[int]:
    values = array("Q")
    values.frombytes(path.read_bytes())
    return values.tolist()


def percentile(ordered: list[int], q: float) -> float:
    """The q-quantile (0..1) of sorted values, nearest rank."""
    if not ordered:
        raise ValueError("no samples")
    return float(ordered[min(len(ordered) - 1, int(q * len(ordered)))])


def case_stats(lat_ns: list[int], runs: list[Record]) -> Record:
    """One case over all its rounds: latency percentiles in µs over every sample, losses,
    and (medians of the rounds) the subscriber's CPU per wait and the publisher's ln_write."""
    ordered = sorted(lat_ns)
    per_wait = [r["cpu_s"] / r["waits"] * 1e6 for r in runs if r["waits"]]
    return {
        "samples": len(ordered),
        "lost": sum(r["lost"] for r in runs),
        "rounds": len(runs),
        "inports": runs[0]["inports"],
        "p50_us": percentile(ordered, 0.5) / 1e3,
        "p90_us": percentile(ordered, 0.9) / 1e3,
        "p99_us": percentile(ordered, 0.99) / 1e3,
        "max_us": ordered[-1] / 1e3,
        "round_p50_us": [r["p50_us"] for r in runs],
        # medians over the rounds: one round with a busy neighbour does not decide
        "cpu_us_per_wait": statistics.median(per_wait) if per_wait else None,
        "write_us": statistics.median(r["write_p50_us"] for r in runs),
        "setup_s": max((r.get("setup_s", 0.0) for r in runs), default=0.0),
    }


def idle_stats(run: Record) -> Record:
    return {**run, "cpu_share": run["cpu_s"] / run["wall_s"]}


def _ratio_goal(
    goal: str, got: Record | None, base: Record | None, key: str, missing: str | None = None
) -> Record:
    if got is None or base is None or not got.get(key) or not base.get(key):
        return {"goal": goal, "status": "MISSING", "why": missing or "a case did not run"}
    ratio = got[key] / base[key]
    return {
        "goal": goal,
        "measured": got[key],
        "baseline": base[key],
        "ratio": ratio,
        "limit": RATIO,
        "status": "PASS" if ratio <= RATIO else "MISS",
    }


def goals(
    summary: dict[str, Record], idle: dict[str, Record], unavailable: dict[str, str]
) -> list[Record]:
    """Issue 29's goals, each against a baseline measured in the same run."""
    rows = [
        _ratio_goal(
            "C waitset p50 <= 1.2x blocking ln_read p50 (1 inport)",
            summary.get("waitset1"),
            summary.get("read"),
            "p50_us",
        ),
        _ratio_goal(
            "Python read_async p50 <= 1.2x blocking sub.read() p50",
            summary.get("py_async"),
            summary.get("py_read"),
            "p50_us",
            unavailable.get("py_async"),
        ),
        _ratio_goal(
            "wake p50 does not grow with N: N=1000 <= 1.2x N=1",
            summary.get("waitset1000"),
            summary.get("waitset1"),
            "p50_us",
        ),
        _ratio_goal(
            "CPU per wait does not grow with N: N=1000 <= 1.2x N=1",
            summary.get("waitset1000"),
            summary.get("waitset1"),
            "cpu_us_per_wait",
        ),
    ]
    ws, base = idle.get("waitset"), idle.get("sleep")
    if ws is None or base is None:
        rows.append(
            {
                "goal": "idle: 100 inports + 1 s timer < 0.1 % CPU",
                "status": "MISSING",
                "why": "an idle process did not run",
            }
        )
    else:
        rows.append(
            {
                "goal": "idle: 100 inports + 1 s timer < 0.1 % CPU",
                "measured": ws["cpu_share"],
                "baseline": base["cpu_share"],
                "limit": IDLE_LIMIT,
                "status": "PASS" if ws["cpu_share"] < IDLE_LIMIT else "MISS",
            }
        )
    return rows


def _f(value: float | None, digits: int = 1) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def latency_table(summary: dict[str, Record], unavailable: dict[str, str]) -> list[str]:
    head = (
        f"{'case':<44} {'inports':>7} {'samples':>7} {'lost':>4} {'p50 µs':>7} "
        f"{'p90 µs':>7} {'p99 µs':>7} {'max µs':>7} {'CPU µs/wait':>11} {'write µs':>8}"
    )
    lines = [head, "-" * len(head)]
    for case, (label, _lang) in CASES.items():
        s = summary.get(case)
        if s is None:
            why = unavailable.get(case, "did not run")
            lines.append(f"{label:<44} missing: {why}")
            continue
        lines.append(
            f"{label:<44} {s['inports']:>7} {s['samples']:>7} {s['lost']:>4} "
            f"{_f(s['p50_us']):>7} {_f(s['p90_us']):>7} {_f(s['p99_us']):>7} "
            f"{_f(s['max_us']):>7} {_f(s['cpu_us_per_wait'], 2):>11} {_f(s['write_us'], 2):>8}"
        )
    return lines


def idle_table(idle: dict[str, Record], inports: int) -> list[str]:
    head = f"{'idle process':<44} {'wall s':>7} {'CPU ms':>7} {'CPU %':>7} {'wake-ups':>8}"
    lines = [head, "-" * len(head)]
    labels = {
        "waitset": f"waitset: {inports} inports + 1 s timer",
        "sleep": f"baseline: {inports} inports, clock_nanosleep",
    }
    for kind, label in labels.items():
        s = idle.get(kind)
        if s is None:
            lines.append(f"{label:<44} missing")
            continue
        lines.append(
            f"{label:<44} {s['wall_s']:>7.1f} {s['cpu_s'] * 1e3:>7.2f} "
            f"{s['cpu_share'] * 100:>7.4f} {s['wakeups']:>8}"
        )
    return lines


def goals_table(rows: list[Record]) -> list[str]:
    lines = [f"{'goal':<56} {'measured':>10} {'baseline':>10} {'ratio':>6}  result", "-" * 92]
    for g in rows:
        if g["status"] == "MISSING":
            lines.append(f"{g['goal']:<56} {'':>10} {'':>10} {'':>6}  MISSING ({g['why']})")
            continue
        share = "ratio" not in g
        fmt = (lambda v: f"{v * 100:.4f} %") if share else (lambda v: f"{v:.2f}")
        ratio = "" if share else f"{g['ratio']:.2f}"
        lines.append(
            f"{g['goal']:<56} {fmt(g['measured']):>10} {fmt(g['baseline']):>10} "
            f"{ratio:>6}  {g['status']}"
        )
    return lines
