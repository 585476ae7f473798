"""`ln_pull_serial`: the host side of a microcontroller's pull subscription
(firmware/pull_mcu, docs/pull.md "On a microcontroller").  It relays SLIP frames between the
serial port of the device (QEMU's `-serial tcp:...,server` chardev, or a unix socket) and an
ln_daemon's UDP pull port (or an `ln_relay` in front of it), sends the host's clock to the
device 4 times a second, and prints the device's text lines on stdout.  Frames start with their
kind: P an NDN packet (both ways), C the host's CLOCK_REALTIME µs (u64 LE, to the device),
T a text line (from the device).  Bad frames are dropped and counted, never fatal."""

from __future__ import annotations

import argparse
import json
import selectors
import signal
import socket
import struct
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from types import FrameType
from typing import TextIO

from . import slip

PROG = "ln_pull_serial"
PACKET, CLOCK, TEXT = ord("P"), ord("C"), ord("T")
MAX_DATAGRAM = 65535
# Bytes waiting for the device, at most: past that a frame is dropped (counted), as a real
# link's buffer would, so that a flood never blocks the gateway's reading of the device.
MAX_PENDING = 64 * 1024


@dataclass
class Counters:
    frames_in: int = 0  # complete frames from the device
    text_lines: int = 0
    packets_up: int = 0  # NDN packets sent to the daemon
    packets_down: int = 0  # datagrams from the daemon sent to the device
    clock_frames: int = 0
    unknown_kind: int = 0  # frames from the device of no known kind
    oversized: int = 0  # frames from the device longer than --max-frame
    bad_escape: int = 0
    foreign: int = 0  # datagrams from another address than the daemon's
    send_errors: int = 0  # packets the daemon's address refused (e.g. no route)
    injected: int = 0  # datagrams of --inject, sent to the device as P frames
    injected_raw: int = 0  # datagrams of --inject-raw, written to the serial line as they are
    dropped: int = 0  # frames for the device dropped: MAX_PENDING bytes were waiting


def parse_host_port(text: str) -> tuple[str, int]:
    host, sep, port = text.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 <= int(port) <= 65535:
        raise argparse.ArgumentTypeError(f"{text!r} is not HOST:PORT")
    return host, int(port)


def open_serial(spec: str, timeout: float) -> socket.socket:
    """Connects to `tcp:HOST:PORT` or `unix:PATH`, retrying until `timeout` (QEMU may not
    listen yet)."""
    kind, _, where = spec.partition(":")
    if kind == "tcp":
        family, address = socket.AF_INET, parse_host_port(where)
    elif kind == "unix" and where:
        family, address = socket.AF_UNIX, where  # type: ignore[assignment]
    else:
        raise SystemExit(f"{PROG}: --serial {spec!r}: expected tcp:HOST:PORT or unix:PATH")
    deadline = time.monotonic() + timeout
    while True:
        sock = socket.socket(family, socket.SOCK_STREAM)
        try:
            sock.connect(address)
            return sock
        except OSError as exc:
            sock.close()
            if time.monotonic() > deadline:
                raise SystemExit(f"{PROG}: cannot connect to {spec}: {exc}") from None
            time.sleep(0.05)


def udp_socket(address: str, port: int) -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind((address, port))
    sock.setblocking(False)
    return sock


class Gateway:
    """One device, one daemon: run() relays until the device closes the line or stop()."""

    def __init__(
        self,
        serial: socket.socket,
        daemon: tuple[str, int],
        out: TextIO,
        max_frame: int = 2048,
        clock_interval: float = 0.25,
    ) -> None:
        self.serial, self.out = serial, out
        info = socket.getaddrinfo(daemon[0], daemon[1], socket.AF_INET, socket.SOCK_DGRAM)
        self.daemon = info[0][4][:2]
        self.udp = udp_socket("0.0.0.0", 0)
        self.decoder = slip.Decoder(max_frame=max_frame)
        self.counters = Counters()
        self.clock_interval = clock_interval
        self.inject: socket.socket | None = None
        self.inject_raw: socket.socket | None = None
        self.stopping = False
        self.device_done = False
        self.pending = bytearray()  # for the device; the serial socket does not block
        serial.setblocking(False)

    def stop(self) -> None:
        self.stopping = True

    def to_device(self, kind: int, payload: bytes, raw: bool = False) -> None:
        if self.device_done:
            return
        data = payload if raw else slip.encode(bytes([kind]) + payload)
        if len(self.pending) + len(data) > MAX_PENDING:
            self.counters.dropped += 1
        else:
            self.pending += data
            self.flush()

    def flush(self) -> None:
        """Writes what the serial socket takes now."""
        try:
            sent = self.serial.send(self.pending)
        except BlockingIOError:
            sent = 0
        del self.pending[:sent]

    def from_device(self, data: bytes) -> None:
        for frame in self.decoder.feed(data):
            self.counters.frames_in += 1
            if frame[0] == PACKET:
                try:
                    self.udp.sendto(frame[1:], self.daemon)
                    self.counters.packets_up += 1
                except OSError:  # a lost packet, as on any link: the device asks again
                    self.counters.send_errors += 1
            elif frame[0] == TEXT:
                self.counters.text_lines += 1
                line = frame[1:].decode("ascii", "replace")
                print(line, file=self.out, flush=True)
                # the device ends after "done": nothing more for it, so that it finds the
                # line empty and QEMU closes it cleanly (no reset dropping its last lines)
                self.device_done |= line.startswith("done ")
            else:
                self.counters.unknown_kind += 1
        self.counters.oversized = self.decoder.oversized
        self.counters.bad_escape = self.decoder.bad_escape

    def _datagram(self, sock: socket.socket) -> None:
        try:
            data, sender = sock.recvfrom(MAX_DATAGRAM)
        except OSError:  # e.g. ICMP port unreachable reported on the socket
            return
        if sock is self.inject_raw:
            self.counters.injected_raw += 1
            self.to_device(0, data, raw=True)
        elif sock is self.inject:
            self.counters.injected += 1
            self.to_device(PACKET, data)
        elif sender[:2] != self.daemon:
            self.counters.foreign += 1
        else:
            self.counters.packets_down += 1
            self.to_device(PACKET, data)

    def send_clock(self) -> None:
        self.to_device(CLOCK, struct.pack("<Q", time.time_ns() // 1000))
        self.counters.clock_frames += 1

    def run(self) -> None:
        sel = selectors.DefaultSelector()
        sel.register(self.serial, selectors.EVENT_READ)
        for sock in (self.udp, self.inject, self.inject_raw):
            if sock is not None:
                sel.register(sock, selectors.EVENT_READ)
        next_clock = 0.0
        while not self.stopping:
            now = time.monotonic()
            if now >= next_clock:
                self.send_clock()
                next_clock = now + self.clock_interval
            events = selectors.EVENT_READ | (selectors.EVENT_WRITE if self.pending else 0)
            sel.modify(self.serial, events)
            for key, mask in sel.select(timeout=min(0.2, max(0.0, next_clock - now))):
                if key.fileobj is not self.serial:
                    self._datagram(key.fileobj)  # type: ignore[arg-type]
                    continue
                if mask & selectors.EVENT_WRITE:
                    self.flush()
                if mask & selectors.EVENT_READ and not self._read_device():
                    return  # the device (QEMU) has gone

    def _read_device(self) -> bool:
        """Takes what the device sent; False once it has closed the line."""
        try:
            data = self.serial.recv(1 << 16)
        except BlockingIOError:
            return True
        except ConnectionResetError:
            data = b""
        if data:
            self.from_device(data)
        return bool(data)


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--serial",
        required=True,
        help="the device's serial line: tcp:HOST:PORT (QEMU -serial "
        "tcp:HOST:PORT,server) or unix:PATH",
    )
    ap.add_argument(
        "--daemon",
        required=True,
        type=parse_host_port,
        help="HOST:PORT of the daemon's UDP pull port (or of an ln_relay)",
    )
    ap.add_argument(
        "--max-frame",
        type=int,
        default=2048,
        help="longest frame accepted from the device, in bytes (default 2048)",
    )
    ap.add_argument(
        "--clock-interval",
        type=float,
        default=0.25,
        help="seconds between clock frames to the device (default 0.25)",
    )
    ap.add_argument(
        "--connect-timeout",
        type=float,
        default=10.0,
        help="seconds to retry connecting to the serial line (default 10)",
    )
    ap.add_argument(
        "--inject",
        type=int,
        metavar="PORT",
        help="also send every UDP datagram to 127.0.0.1:PORT to the device as a packet (for tests)",
    )
    ap.add_argument(
        "--inject-raw",
        type=int,
        metavar="PORT",
        help="write every UDP datagram to 127.0.0.1:PORT on the serial line as "
        "it is, unframed (for tests)",
    )
    ap.add_argument(
        "--stats-file", type=Path, help="write the counters there as JSON when the gateway ends"
    )
    return ap.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    if args.max_frame < 1 or not args.clock_interval > 0:
        raise SystemExit(f"{PROG}: --max-frame and --clock-interval must be > 0")
    serial = open_serial(args.serial, args.connect_timeout)
    try:
        gw = Gateway(serial, args.daemon, sys.stdout, args.max_frame, args.clock_interval)
    except OSError as exc:  # e.g. a host name that does not resolve
        raise SystemExit(f"{PROG}: --daemon {args.daemon[0]}:{args.daemon[1]}: {exc}") from None
    if args.inject is not None:
        gw.inject = udp_socket("127.0.0.1", args.inject)
    if args.inject_raw is not None:
        gw.inject_raw = udp_socket("127.0.0.1", args.inject_raw)

    def on_signal(signum: int, frame: FrameType | None) -> None:
        gw.stop()

    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    try:
        gw.run()
    except OSError as exc:  # the serial line broke
        print(f"{PROG}: serial line: {exc}", file=sys.stderr)
    finally:
        stats = asdict(gw.counters)
        print(f"{PROG}: " + " ".join(f"{k}={v}" for k, v in stats.items()), file=sys.stderr)
        if args.stats_file is not None:
            args.stats_file.write_text(json.dumps(stats) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
