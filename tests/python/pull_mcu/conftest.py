"""Fixtures of the microcontroller tests (docs/pull.md, "On a microcontroller"): the
firmware of firmware/pull_mcu running in QEMU (`-M mps2-an385`) on host b of the network
tests' multi-host system (tests/python/network/conftest.py), its ln_pull_serial gateway
beside it, and what the firmware printed, parsed.  They need qemu-system-arm and
arm-none-eabi-gcc (scripts/setup installs both): a failure in CI without them, a skip
elsewhere."""

from __future__ import annotations

import re
import shutil
import sys
from dataclasses import dataclass

import pytest
from buildtree import REPO, missing_test_tool
from netlab import Host, HostProcess
from network.conftest import system  # noqa: F401 - the fixture, shared
from polling import wait_for

# the release build's (firmware/SConscript builds no other variant; a sanitizer has nothing
# to watch in it)
FIRMWARE = REPO / "build" / "release" / "firmware" / "pull_mcu"
ELF = FIRMWARE / "pull_mcu.elf"
TOPIC = "arm.state"  # the firmware's default topic, /ln/robot/arm.state
PREFIX = "/ln/robot"
PULL_PORT = 6363
SERIAL_PORT = 45400  # QEMU's serial server inside host b (a network stack of its own)
_SAMPLE = re.compile(r"s (\d+) (-?\d+|-) (\d+) ([0-9a-f]{8})$")
_STATS = re.compile(r"(stats|done) (.*)$")
_RAM = re.compile(r"pull_mcu \S+ ram data=(\d+) bss=(\d+) stack=(\d+) sub=(\d+)$")


@dataclass
class Sample:
    seq: int
    age_ms: int | None  # None: printed before the first clock frame
    size: int
    crc: int


def _without_sanitizer(env: dict[str, str]) -> dict[str, str]:
    """QEMU is not ours: the sanitized run's preloaded ASan runtime would only report on its
    coroutines (makecontext/swapcontext), so it runs without it."""
    return {k: v for k, v in env.items() if k != "LD_PRELOAD"}


class Device:
    """QEMU running the firmware and ln_pull_serial relaying its UART to `daemon`."""

    def __init__(self, host: Host, daemon: str, *gateway_args: str) -> None:
        if not ELF.exists():
            pytest.fail(f"{ELF} is missing: run scons (with arm-none-eabi-gcc installed)")
        self.qemu: HostProcess = host.popen(
            [
                "qemu-system-arm",
                "-M",
                "mps2-an385",
                "-nographic",
                "-monitor",
                "none",
                "-semihosting-config",
                "enable=on,target=native",
                "-kernel",
                str(ELF),
                "-serial",
                f"tcp:127.0.0.1:{SERIAL_PORT},server=on,wait=on",
            ],
            env=_without_sanitizer(host.env()),
            log="qemu.log",
        )
        self.gateway: HostProcess = host.popen(
            [
                sys.executable,
                "-m",
                "links_and_nodes.tools.pull_serial",
                "--serial",
                f"tcp:127.0.0.1:{SERIAL_PORT}",
                "--daemon",
                daemon,
                *gateway_args,
            ],
            log="gateway.log",
        )

    def lines(self) -> list[str]:
        assert self.gateway.log_path is not None
        return self.gateway.log_path.read_text(errors="replace").splitlines()

    def samples(self) -> list[Sample]:
        out = []
        for m in map(_SAMPLE.match, self.lines()):
            if m:
                out.append(
                    Sample(int(m[1]), None if m[2] == "-" else int(m[2]), int(m[3]), int(m[4], 16))
                )
        return out

    def stats(self) -> list[dict[str, int]]:
        """Every "stats" and the "done" line, as dicts."""
        return [
            {k: int(v) for k, v in (kv.split("=") for kv in m[2].split())}
            for m in map(_STATS.match, self.lines())
            if m
        ]

    def ram(self) -> tuple[int, int, int, int]:
        """(data, bss, stack, sizeof ln_pull_sub) of the start line."""
        for m in map(_RAM.match, self.lines()):
            if m:
                return int(m[1]), int(m[2]), int(m[3]), int(m[4])
        raise AssertionError(f"no start line in {self.lines()[:5]}")

    def wait_done(self, timeout: float) -> None:
        """Until QEMU has ended by itself (the firmware's semihosting exit after "done")."""
        wait_for(
            lambda: self.qemu.poll() is not None, "the firmware to end its run", timeout=timeout
        )
        assert self.qemu.returncode == 0, f"QEMU exit status {self.qemu.returncode}"
        self.gateway.wait(timeout=10)
        assert any(line.startswith("done ") for line in self.lines()), self.lines()[-5:]

    def close(self) -> None:
        for proc in (self.qemu, self.gateway):
            if proc.poll() is None:
                proc.kill()
            proc.wait()


def require_tools() -> None:
    for tool in ("qemu-system-arm", "arm-none-eabi-gcc"):
        if shutil.which(tool) is None:
            missing_test_tool(
                f"{tool} (scripts/setup installs qemu-system-arm and gcc-arm-none-eabi)"
            )


def topic_config(port: int = PULL_PORT) -> str:
    return f"topics\n{TOPIC}: pull:ndn-udp, pull_port:{port}, pull_prefix:{PREFIX}\n"


def process(name: str, node: str, argv: list[str], ready: str = "", depends_on: str = "") -> str:
    lines = [
        f"process {name}",
        f"    node: {node}",
        f"    command: {' '.join(argv)}",
        "    term_timeout: 2",
        "    flags: no_error_on_successful_stop",
    ]
    lines.append(f"    ready_regex: ^{ready}" if ready else f"    depends_on: {depends_on}")
    return "\n".join(lines) + "\n\n"
