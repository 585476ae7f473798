"""The optional peers of the topic benchmark: iceoryx (its C binding program iox_bench, built
only where the headers are installed, and a private iox-roudi with mempools for every size)
and iceoryx2 (the PyPI package).  Each says why it is unavailable instead of failing the run."""

from __future__ import annotations

import importlib.metadata
import importlib.util
import shutil
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path

ROUDI_MGMT = Path("/dev/shm/iceoryx_mgmt")  # RouDi's management segment: one RouDi per host
ROUDI_START_TIMEOUT = 20.0  # seconds; RouDi maps (and partly touches) its whole pool first


def chunk_counts(sizes: list[int], zc_buffers: dict[int, int]) -> dict[int, int]:
    """Chunks per mempool: a ping-pong holds a few, a throughput run its subscriber's queue
    plus what publisher and subscriber hold in hand."""
    return {size: max(16, zc_buffers.get(size, 0) * 2 + 8) for size in sizes}


def roudi_config(sizes: list[int], counts: dict[int, int]) -> str:
    """RouDi's TOML: one mempool per payload size, room for the chunk header (about 40 B)."""
    lines = ["# iox-roudi config written by bench_topics.py: one mempool per benchmark size",
             "[general]", "version = 1", "", "[[segment]]"]
    for size in sizes:
        chunk = (size + 64 + 63) // 64 * 64
        lines += ["", "[[segment.mempool]]", f"size = {chunk}", f"count = {counts[size]}"]
    return "\n".join(lines) + "\n"


@dataclass
class Iceoryx:
    """A private iox-roudi for iox_bench, or the reason there is none."""

    program: Path
    why_not: str | None = None
    version: str | None = None
    process: subprocess.Popen[bytes] | None = None
    log: Path | None = None
    config: dict[int, int] = field(default_factory=dict)

    @classmethod
    def start(cls, program: Path, tmp: Path, sizes: list[int],
              zc_buffers: dict[int, int]) -> Iceoryx:
        roudi = shutil.which("iox-roudi")
        peer = cls(program)
        if not program.exists():
            peer.why_not = (f"{program.name} not built (no iceoryx C binding headers at build "
                            "time: apt-get install iceoryx libiceoryx-binding-c-dev, then scons)")
        elif roudi is None:
            peer.why_not = "iox-roudi not installed (apt-get install iceoryx)"
        elif ROUDI_MGMT.exists():
            peer.why_not = f"another RouDi runs on this host ({ROUDI_MGMT} exists)"
        if peer.why_not:
            return peer
        peer.version = _dpkg_version("iceoryx")
        counts = chunk_counts(sizes, zc_buffers)
        config = tmp / "roudi.toml"
        config.write_text(roudi_config(sizes, counts))
        peer.log = tmp / "roudi.log"
        with open(peer.log, "wb") as log:
            peer.process = subprocess.Popen([roudi, "-c", str(config), "-m", "off",
                                             "-l", "warning"], stdout=log, stderr=log)
        deadline = time.monotonic() + ROUDI_START_TIMEOUT
        while time.monotonic() < deadline and peer.process.poll() is None:
            if ROUDI_MGMT.exists() and _pool_ready(peer.log):
                peer.config = counts
                return peer
            time.sleep(0.1)
        peer.stop()
        peer.why_not = f"iox-roudi did not start: {peer.log.read_text(errors='replace')[-300:]}"
        return peer

    @property
    def available(self) -> bool:
        return self.why_not is None

    def stop(self) -> None:
        if self.process is not None and self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=15)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self.process = None


def _pool_ready(log: Path) -> bool:
    """RouDi logs one "Reserving" line per segment (management, then payload) before it
    accepts applications."""
    return log.read_text(errors="replace").count("Reserving") >= 2


def _dpkg_version(package: str) -> str | None:
    try:
        out = subprocess.run(["dpkg-query", "-W", "-f", "${Version}", package],
                             capture_output=True, text=True, timeout=10)
    except OSError:
        return None
    return out.stdout.strip() or None


def iceoryx2_status() -> tuple[str | None, str | None]:
    """(version, None) if the iceoryx2 Python package imports, else (None, why not)."""
    if importlib.util.find_spec("iceoryx2") is None:
        return None, "iceoryx2 not installed (pip install iceoryx2)"
    try:
        import iceoryx2  # noqa: F401
    except ImportError as exc:
        return None, f"iceoryx2 does not import: {exc}"
    return importlib.metadata.version("iceoryx2"), None

