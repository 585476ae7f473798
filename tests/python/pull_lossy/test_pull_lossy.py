"""Pull topics through a lossy network (docs/pull.md): C publishers on host a at 50 Hz or
500 Hz served by a's ln_daemon as pull topics, and on host b, for each loss of 0, 5 and
20 % per direction (one seeded ln_relay each, 1 ms one-way delay), a consumer with the
seed's naive DIT and one with the hardenings (k = 3, t_max = 100 ms), all at once for the
same run (a topic and a publisher per loss).  The bounds are loose and about behaviour
only: the hardened consumer gets nearly everything without loss, at least what the naive
one gets under loss, never sits at t_max for long, and catches up again after every stall
(the lag behind the publisher comes back near 0 in every second).  The numbers themselves
are bench/pull's."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import pytest
from buildtree import SANITIZED, build_dir
from network.conftest import System
from polling import wait_for

REPO = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(REPO / "bench" / "pull"))
import pull_metrics as pm  # noqa: E402

PROBE = build_dir() / "bench" / "pull" / "pull_probe"
PULL_PORT = 6363
RELAY_BASE = 54600  # on b: 127.0.0.1:RELAY_BASE + 2*i (naive), + 2*i + 1 (hardened)
LOSSES = (0.0, 0.05, 0.2)
DELAY_MS = 1  # RTT stays well below k·P at 500 Hz (k = 3: 6 ms)
DEADLINE_MS = 100
WARMUP_S, RUN_S = 1.5, 6.0
SEED = 14


def _relay(system: System, index: int, loss: float) -> None:
    """ln_relay on b for one loss: two links towards a's pull port (naive, hardened)."""
    b = system.lab["b"]
    target = f"{system.lab['a'].address}:{PULL_PORT}"
    links = [arg for j in (0, 1)
             for arg in ("--udp", f"127.0.0.1:{RELAY_BASE + 2 * index + j}", target)]
    ready = system.tmp / f"relay{index}.json"
    b.popen([sys.executable, "-m", "links_and_nodes.relay.cli", *links, "--loss", str(loss),
             "--delay-ms", str(DELAY_MS), "--seed", str(SEED + index),
             "--ready-file", str(ready)], env=system.env(b), log=f"relay{index}.log")
    wait_for(ready.exists, f"the relay with {loss:.0%} loss to listen")


def _process(name: str, node: str, argv: list[str], ready: str = "",
             depends_on: str = "") -> str:
    lines = [f"process {name}", f"    node: {node}", f"    command: {' '.join(argv)}",
             "    term_timeout: 2", "    flags: no_error_on_successful_stop"]
    lines.append(f"    ready_regex: ^{ready}" if ready else f"    depends_on: {depends_on}")
    return "\n".join(lines) + "\n\n"


def _run(system: System, rate_hz: int) -> dict[str, dict[str, Any]]:
    """Every consumer's pull_probe output, by "<naive|hardened>-<loss>"."""
    if not PROBE.exists():
        pytest.fail(f"{PROBE} is missing: run scons first")
    system.start_daemons("ab")  # a serves the topic, b starts the consumers
    for i, loss in enumerate(LOSSES):
        _relay(system, i, loss)
    # a topic per loss: the producer parks 8 Interests per topic, a naive and a hardened
    # consumer park 1 + 3 (more consumers of one topic would overflow it: NACKs)
    prefix, topics = "/ln/lossy", [f"lossy.r{rate_hz}.l{i}" for i in range(len(LOSSES))]
    procs = "".join(_process(f"pub{i}", "a", [str(PROBE), "pub", topic,
                                              str(1_000_000 // rate_hz)], "ready")
                    for i, topic in enumerate(topics))
    outs = {}
    for i, loss in enumerate(LOSSES):
        for j, kind in enumerate(("naive", "hardened")):
            name = f"{kind}-{loss}"
            outs[name] = system.tmp / f"{name}.json"
            opts = ["--naive"] if kind == "naive" else ["--window", "3", "--deadline",
                                                         str(DEADLINE_MS)]
            procs += _process(f"{kind}{i}", "b", [
                str(PROBE), "pull", f"127.0.0.1:{RELAY_BASE + 2 * i + j}",
                f"{prefix}/{topics[i]}", str(WARMUP_S + RUN_S), str(outs[name]), *opts,
                "--seed", str(SEED + 2 * i + j)], depends_on=f"pub{i}")
    lnc = system.lnc(procs, extra=f"topics\nlossy.*: pull:ndn-udp, pull_port:{PULL_PORT}, "
                                  f"pull_prefix:{prefix}\n")
    system.run(lnc)
    wait_for(lambda: all(p.exists() and p.read_text().endswith("}\n") for p in outs.values()),
             "every consumer to finish its run", timeout=60)
    return {name: json.loads(p.read_text()) for name, p in outs.items()}


@pytest.mark.parametrize("rate_hz", [50, 500])
def test_hardened_dit_through_loss(system: System, rate_hz: int) -> None:
    runs = _run(system, rate_hz)
    # each loss has its own publisher (schedule), so its own window
    windows = {loss: pm.window([runs[f"naive-{loss}"], runs[f"hardened-{loss}"]],
                               1e6 / rate_hz, WARMUP_S) for loss in LOSSES}
    got = {name: pm.metrics(run, windows[float(name.split("-")[1])])
           for name, run in runs.items()}
    table = "\n".join(f"  {n}: delivered {m.delivered:.3f}, AoI mean {m.aoi_mean_ms:.1f} ms, "
                      f"lag {m.lag_max_last_half:.0f}" for n, m in got.items())
    # without loss the hardened consumer gets nearly every sample (the seed's DIT gets about
    # 0.6 at 500 Hz, nearly all at 50 Hz): nearly all, or clearly more than the seed's in the
    # same run; the absolute bound leaves room for a loaded machine (0.67 and 0.47 seen on CI
    # runs with the sanitizer build beside it, the seed's DIT then at 0.1), where the relay (a
    # Python process) holds datagrams back for longer than the consumer's window covers (and
    # slower still under ASan/UBSan)
    hardened, naive = got["hardened-0.0"].delivered, got["naive-0.0"].delivered
    assert hardened >= 0.4, table
    assert hardened >= min(naive + 0.1, 0.95), table
    # under loss it gets at least what the seed's DIT gets (a margin for noise)
    for loss in (0.05, 0.2):
        assert got[f"hardened-{loss}"].delivered >= got[f"naive-{loss}"].delivered - 0.05, \
            table
    for loss in LOSSES:
        run = runs[f"hardened-{loss}"]
        # after the start-up, t never sits at t_max for more than 3 timeouts in a row (a
        # window's slots, expiring a period apart, are one round)
        stuck = pm.runs_at_t_max(run, DEADLINE_MS, together_us=1e6 / rate_hz,
                                 since_us=windows[loss].start_us)
        assert stuck <= 3, f"{loss:.0%}: {stuck} timeouts in a row at t_max"
        # no unbounded growth: in every second of the second half it catches up again, to
        # within 80 ms of samples (72 ms seen on a loaded CI run, where the relay, a Python
        # process, stalls; growth without bound would be seconds), 120 ms under ASan/UBSan
        floors = pm.lag_floors(run, windows[loss])
        bound = max(3, (120 if SANITIZED else 80) * rate_hz // 1000)
        assert max(floors) <= bound, f"{loss:.0%}: lag floors {floors}"
        assert run["stats"]["bad"] == 0, run["stats"]
