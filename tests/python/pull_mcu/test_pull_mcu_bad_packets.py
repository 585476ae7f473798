"""Bad packets at the firmware (docs/pull.md, "On a microcontroller"): while firmware/pull_mcu
pulls arm.state in QEMU, a few thousand mutated Data packets for its topic (bytes flipped,
truncated, from well-formed packets of the seqs it is about to ask for) go to it through the
gateway, and raw bytes that are no valid SLIP (bad escapes, oversized frames, noise) go to
its serial line as they are.  It keeps running, counts what it dropped, and still delivers
the publisher's samples, with the right payload, afterwards."""

from __future__ import annotations

import random
import struct
import sys
import time
import zlib

import pytest
from buildtree import build_dir
from network.conftest import System
from polling import wait_for
from pull import ndn_wire as w

from .conftest import PREFIX, PULL_PORT, TOPIC, Device, process, require_tools, topic_config

PROBE = build_dir() / "bench" / "pull" / "pull_probe"
INJECT, INJECT_RAW = 45402, 45403  # the gateway's test ports on b
MUTANTS = 3000
SEED = 32


def _mutants(rng: random.Random, around: int) -> list[bytes]:
    out = []
    for i in range(MUTANTS):
        seq = around + rng.randrange(-5, 20)
        content = w.pull_content(
            seq + rng.randrange(0, 3), time.time_ns() // 1000, 20_000, rng.randbytes(64)
        )
        p = bytearray(w.data(w.name_value(f"{PREFIX}/{TOPIC}", seq), content))
        if i % 3 == 0:
            p = p[: rng.randrange(1, len(p))]  # truncated
        for _ in range(rng.randrange(1, 4)):  # flipped bytes
            p[rng.randrange(len(p))] ^= 1 << rng.randrange(8)
        out.append(bytes(p))
    return out


def _raw(rng: random.Random) -> list[bytes]:
    """Serial noise: bad escapes, a frame longer than the firmware's buffer, random bytes;
    every one ends with END so that the line is in sync again afterwards."""
    return [
        b"\xc0P\xdb\x01\x02\xc0",
        b"\xc0" + b"P" + bytes(600) + b"\xc0",
        b"\xc0\xdb\xc0",
        b"\xc0X123\xc0",
    ] + [rng.randbytes(rng.randrange(1, 200)) + b"\xc0" for _ in range(200)]


def test_firmware_survives_bad_packets(system: System) -> None:
    require_tools()
    if not PROBE.exists():
        pytest.fail(f"{PROBE} is missing: run scons first")
    system.start_daemon("a")
    procs = process("pub", "a", [str(PROBE), "pub", TOPIC, "20000"], "ready")
    system.run(system.lnc(procs, extra=topic_config()))
    b = system.lab["b"]
    device = Device(
        b,
        f"{system.lab['a'].address}:{PULL_PORT}",
        "--inject",
        str(INJECT),
        "--inject-raw",
        str(INJECT_RAW),
    )
    try:
        wait_for(lambda: len(device.samples()) >= 50, "the firmware's first samples", timeout=30)
        rng = random.Random(SEED)
        latest = device.samples()[-1].seq
        # sent from inside host b (its own network stack)
        script = (
            "import socket, sys, ast\n"
            "s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)\n"
            "for port, p in ast.literal_eval(sys.stdin.read()):\n"
            "    s.sendto(p, ('127.0.0.1', port))\n"
        )
        packets = [(INJECT, p) for p in _mutants(rng, latest)]
        packets += [(INJECT_RAW, p) for p in _raw(rng)]
        rng.shuffle(packets)
        b.run([sys.executable, "-c", script], input=repr(packets), check=True)
        sent_at = len(device.samples())
        # afterwards it still pulls: 100 more samples (2 s at 50 Hz), well-formed
        wait_for(
            lambda: len(device.samples()) >= sent_at + 100,
            "samples after the bad packets",
            timeout=30,
        )
        assert device.qemu.poll() is None, "QEMU ended"
        stats = device.stats()[-1]
    finally:
        device.close()
    after = device.samples()[sent_at:]
    good = [
        s
        for s in after
        if s.crc == zlib.crc32(struct.pack("<Q", s.seq) + bytes(56)) and s.size == 64
    ]
    assert len(good) >= 90, f"{len(good)} of {len(after)} later samples as published"
    print(f"after the bad packets: {len(good)} of {len(after)} samples as published; {stats}")
    assert stats["bad"] + stats["late"] + stats["foreign"] > 0, stats  # the mutants were seen
    assert stats["frames_bad"] > 0, stats  # and the serial noise
