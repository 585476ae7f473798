"""The pull consumer as firmware (docs/pull.md, "On a microcontroller"): firmware/pull_mcu
in QEMU on host b pulls arm.state, published at 50 Hz on host a, through ln_pull_serial and
an ln_relay with 0 % or 20 % loss per direction (seeded, 1 ms delay); a push subscriber on b
gets the same topic through the same relay (b's data port behind it) in the same run.
Over 20 s of samples after 2 s of start-up: at 0 % loss the firmware gets ≥ 95 % of them,
at 20 % at least 0.9× what push gets; every age is within the bound docs/pull.md states;
every payload's CRC-32 is that of what was published; the stack high-water mark the
firmware measured stays within the static figure of its call graph (scripts/stack-chain),
and the RAM it reports is what its linker map says."""

from __future__ import annotations

import json
import re
import statistics
import struct
import sys
import zlib
from pathlib import Path

import pytest
from buildtree import build_dir, not_under_sanitizers
from network.conftest import System
from polling import wait_for

from .conftest import FIRMWARE, PULL_PORT, TOPIC, Device, process, require_tools, topic_config
from .stack_static import firmware_stack_bound

PROBE = build_dir() / "bench" / "pull" / "pull_probe"
PERIOD_US = 20_000  # 50 Hz
WARMUP, SAMPLES = 100, 1000  # 2 s of start-up, then 20 s
DATA_PORT = 54377  # the daemons' forwarding port
RELAY_DATA = 54400  # b's data port as advertised: the relay, in front of it
RELAY_PULL = 45401  # on b: the relay's way to a's pull port, for the gateway
DELAY_MS = 1
SEED = 32
# docs/pull.md, the ages' bounds: never below -3 ms (the clock sync takes the smallest
# delay of the gateway's clock frames, so it never runs ahead; 1 ms steps on both sides), at
# most 1 s (a lost Interest is sent again after t <= t_max = 100 ms, and once a newer sample
# is delivered an older one is late), and without loss a median of at most half the deadline
AGE_MIN_MS, AGE_MAX_MS, MEDIAN_NO_LOSS_MS = -3, 1000, 50


def _relay(system: System, loss: float) -> None:
    b = system.lab["b"]
    ready = system.tmp / "relay.json"
    data = ["127.0.0.1:" + str(DATA_PORT)]
    b.popen(
        [
            sys.executable,
            "-m",
            "links_and_nodes.relay.cli",
            "--udp",
            f"{b.address}:{RELAY_DATA}",
            *data,
            "--tcp",
            f"{b.address}:{RELAY_DATA}",
            *data,
            "--udp",
            f"127.0.0.1:{RELAY_PULL}",
            f"{system.lab['a'].address}:{PULL_PORT}",
            "--loss",
            str(loss),
            "--delay-ms",
            str(DELAY_MS),
            "--seed",
            str(SEED),
            "--ready-file",
            str(ready),
        ],
        env=system.env(b),
        log="relay.log",
    )
    wait_for(ready.exists, f"the relay with {loss:.0%} loss to listen")


def _published_crc(seq: int) -> int:
    """pull_probe pub writes lnbench/sample_64 with counter = seq and zeros after it."""
    return zlib.crc32(struct.pack("<Q", seq) + bytes(56))


def _map_sizes(path: Path) -> dict[str, int]:
    """Sizes of the output sections .data, .bss and .stack in a GNU ld map."""
    found = re.findall(r"^\.(data|bss|stack)\s+0x[0-9a-f]+\s+0x([0-9a-f]+)", path.read_text(), re.M)
    return {name: int(size, 16) for name, size in found}


def _delivered(seqs: set[int], first: int) -> float:
    window = range(first + WARMUP, first + WARMUP + SAMPLES)
    return sum(1 for s in window if s in seqs) / SAMPLES


@not_under_sanitizers("an emulated CPU's delivery ratio on a machine the sanitized run "
                      "starves; the daemon's pull path runs sanitized in pull_lossy and the "
                      "bad-packet test")
@pytest.mark.parametrize("loss", [0.0, 0.2])
def test_firmware_pulls_through_loss(system: System, loss: float) -> None:
    require_tools()
    if not PROBE.exists():
        pytest.fail(f"{PROBE} is missing: run scons first")
    system.start_daemon("a", "--data-port", str(DATA_PORT))
    system.start_daemon(
        "b", "--data-port", str(DATA_PORT), "--advertise-data-port", str(RELAY_DATA)
    )
    _relay(system, loss)
    push_out = system.tmp / "push.json"
    procs = process("pub", "a", [str(PROBE), "pub", TOPIC, str(PERIOD_US)], "ready")
    # push runs past the firmware's 25 s (it starts a moment before it)
    procs += process(
        "push", "b", [str(PROBE), "push", TOPIC, "30", str(push_out)], depends_on="pub"
    )
    system.run(system.lnc(procs, extra=topic_config()))
    device = Device(system.lab["b"], f"127.0.0.1:{RELAY_PULL}")
    try:
        device.wait_done(timeout=60)
    finally:
        device.close()
    samples = device.samples()
    assert samples, device.lines()[-20:]
    first = samples[0].seq
    got = _delivered({s.seq for s in samples}, first)
    report = f"firmware delivered {got:.3f} at {loss:.0%} loss; last: {device.lines()[-1]}"

    # checksums, ages and the order of every sample
    seqs = [s.seq for s in samples]
    assert seqs == sorted(set(seqs)), "samples out of order or repeated"
    wrong = [s.seq for s in samples if s.crc != _published_crc(s.seq) or s.size != 64]
    assert not wrong, f"payloads differ from what was published: seqs {wrong[:10]}"
    # ages in the window (the clock estimate settles in the first seconds)
    ages = [s.age_ms for s in samples if s.age_ms is not None and s.seq >= first + WARMUP]
    assert len(ages) >= got * SAMPLES, "no age: the gateway's clock frames did not arrive"
    assert all(AGE_MIN_MS <= a <= AGE_MAX_MS for a in ages), f"ages {min(ages)}..{max(ages)}"

    if loss == 0.0:
        assert got >= 0.95, report
        assert statistics.median(ages) <= MEDIAN_NO_LOSS_MS, f"median age {statistics.median(ages)}"
    else:
        wait_for(
            lambda: push_out.exists() and push_out.read_text().endswith("}\n"),
            "the push subscriber to finish",
            timeout=30,
        )
        push = {int(r[0]) for r in json.loads(push_out.read_text())["samples"]}
        pushed = _delivered(push, first)
        assert pushed > 0.5, f"push delivered {pushed:.3f}"
        assert got >= 0.9 * pushed, f"{report}, push {pushed:.3f}"
        print(f"push delivered {pushed:.3f}")

    print(f"{report}; ages median {statistics.median(ages)} ms, max {max(ages)} ms")
    # the stack: the measured high-water mark within the static figure of the call graph
    done = device.stats()[-1]
    bound = firmware_stack_bound(FIRMWARE)
    assert 0 < done["stack"] <= bound.total, f"high-water mark {done['stack']}, {bound}"
    print(f"stack high-water mark {done['stack']} B, static bound {bound}")
    assert done["bad"] == 0 and done["frames_bad"] == 0, done
    # its RAM as it reports it is what the linker map says
    data, bss, stack, _ = device.ram()
    assert _map_sizes(FIRMWARE / "pull_mcu.map") == {"data": data, "bss": bss, "stack": stack}
