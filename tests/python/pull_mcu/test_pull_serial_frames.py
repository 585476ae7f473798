"""The gateway's side of the serial line (ln_pull_serial, links_and_nodes.tools.slip): SLIP
frames round-trip whatever their bytes; an oversized frame, a bad escape or a frame of an
unknown kind is dropped and counted and the next frame gets through; the device's packets
go to the daemon's address and its text lines to the output; a device that reads slowly
never blocks the gateway."""

from __future__ import annotations

import io
import random
import socket

from links_and_nodes.tools import slip
from links_and_nodes.tools.pull_serial import MAX_PENDING, PACKET, Gateway


def test_frames_round_trip_in_any_chunks() -> None:
    rng = random.Random(7)
    frames = [rng.randbytes(rng.randrange(1, 300)) for _ in range(200)]
    frames += [bytes([slip.END, slip.ESC, slip.ESC_END, slip.ESC_ESC]) * 10]
    wire = b"".join(slip.encode(f) for f in frames)
    dec, got, pos = slip.Decoder(), [], 0
    while pos < len(wire):
        step = rng.randrange(1, 50)
        got += dec.feed(wire[pos : pos + step])
        pos += step
    assert got == frames
    assert (dec.oversized, dec.bad_escape) == (0, 0)


def test_bad_frames_are_dropped_and_counted() -> None:
    dec = slip.Decoder(max_frame=16)
    out = dec.feed(bytes([slip.END, 1, slip.ESC, 7, 2, slip.END]))  # bad escape
    out += dec.feed(bytes([slip.END]) + bytes(17) + bytes([slip.END]))  # oversized
    out += dec.feed(bytes([9, slip.ESC, slip.END]))  # ESC right before END
    out += dec.feed(slip.encode(b"ok"))
    assert out == [b"ok"]
    assert (dec.bad_escape, dec.oversized) == (2, 1)


def test_gateway_routes_and_survives_garbage() -> None:
    device, gateway_end = socket.socketpair()
    daemon = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    daemon.bind(("127.0.0.1", 0))
    daemon.settimeout(5)
    out = io.StringIO()
    gw = Gateway(gateway_end, daemon.getsockname(), out, max_frame=64)
    try:
        rng = random.Random(3)
        for _ in range(500):
            gw.from_device(rng.randbytes(rng.randrange(1, 100)))
        gw.from_device(bytes([slip.END]))  # back in step
        gw.from_device(slip.encode(b"Thello") + slip.encode(b"P\x05\x01\x00") + slip.encode(b"X"))
        assert out.getvalue().endswith("hello\n")
        received = [daemon.recv(100) for _ in range(gw.counters.packets_up)]
        assert received[-1] == b"\x05\x01\x00"  # after any the garbage made
        c = gw.counters
        assert c.unknown_kind >= 1 and c.oversized + c.bad_escape > 0, c
    finally:
        for s in (device, gateway_end, daemon, gw.udp):
            s.close()


def test_gateway_never_blocks_on_a_slow_device() -> None:
    """A device that reads nothing: frames queue up to MAX_PENDING bytes, the rest are
    dropped and counted; what was queued arrives whole once the device reads."""
    device, gateway_end = socket.socketpair()
    out = io.StringIO()
    gw = Gateway(gateway_end, ("127.0.0.1", 9), out)
    try:
        for i in range(3000):
            gw.to_device(PACKET, bytes([i % 256]) * 200)
        assert gw.counters.dropped > 0
        assert len(gw.pending) <= MAX_PENDING
        device.setblocking(False)
        dec, frames = slip.Decoder(), []
        while True:
            try:
                frames += dec.feed(device.recv(1 << 16))
            except BlockingIOError:
                if not gw.pending:
                    break
                gw.flush()
        assert len(frames) == 3000 - gw.counters.dropped
        assert all(f == bytes([PACKET]) + f[1:2] * 200 for f in frames)
    finally:
        for s in (device, gateway_end, gw.udp):
            s.close()
