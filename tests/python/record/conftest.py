"""Fixtures of the recording tests: a private ln_manager per test (unique instance, free
port, own runtime dir), ln_record and ln_play run as the commands they are (`python -m`),
the test message definitions, and the independent MCAP readers the files are checked with."""

from __future__ import annotations

import os
import subprocess
import sys
import uuid
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest
from buildtree import missing_test_tool
from polling import wait_for

import links_and_nodes as ln
from links_and_nodes.manager.frontends import launch
from links_and_nodes.manager.frontends.launch import ManagerProcess, segments

HERE = Path(__file__).resolve().parent
MD_DIR = HERE / "md"  # rectest/sample, rectest/tool (imports robot/pose and rectest/stamp)
MD_CHANGED = HERE / "md_changed"  # rectest/sample with another layout

ln.add_message_definition_dir(MD_DIR)


@dataclass
class Lab:
    """A test's manager, its directory and the commands started against it."""

    process: ManagerProcess
    tmp: Path
    procs: list[subprocess.Popen[bytes]] = field(default_factory=list)

    @property
    def address(self) -> str:
        return self.process.address

    def client(self, name: str = "test") -> ln.client:
        return ln.client(name, self.address)

    def env(self, **extra: str) -> dict[str, str]:
        return {**self.process.env, **extra}

    def record(self, *args: str, log: str = "record.log") -> subprocess.Popen[bytes]:
        """ln_record -o TMP/out ARGS..., its stderr into TMP/LOG."""
        with open(self.tmp / log, "wb") as err:
            proc = subprocess.Popen(
                [sys.executable, "-m", "links_and_nodes.record.record_cli", "-o",
                 str(self.tmp / "out"), "--md-dir", str(MD_DIR), "--poll", "0.1", *args],
                stdout=subprocess.DEVNULL, stderr=err, env=self.env())
        self.procs.append(proc)
        return proc

    def play(self, *args: str, md_dir: Path | None = MD_DIR,
             timeout: float = 120.0) -> subprocess.CompletedProcess[str]:
        """ln_play ARGS... to its end (`timeout` only bounds a hang)."""
        extra = ["--md-dir", str(md_dir)] if md_dir is not None else []
        return subprocess.run(
            [sys.executable, "-m", "links_and_nodes.record.play_cli", *extra, *args],
            capture_output=True, text=True, env=self.env(), timeout=timeout)

    def files(self) -> list[Path]:
        return sorted((self.tmp / "out").glob("*.mcap"))

    def log(self, name: str = "record.log") -> str:
        return (self.tmp / name).read_text(errors="replace")


@pytest.fixture
def lab(tmp_path: Path) -> Iterator[Lab]:
    instance = f"r{os.getpid()}x{uuid.uuid4().hex[:8]}"
    process = launch.start_manager(instance, tmp_path / "runtime", tmp_path / "manager.log")
    lab = Lab(process, tmp_path)
    try:
        yield lab
    finally:
        for proc in lab.procs:  # whatever a failed test left running
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        code = process.stop()
    assert code == 0
    assert segments(instance) == []


def wait_subscribed(pub: Any, count: int = 1) -> None:
    wait_for(lambda: pub.subscriber_count >= count, "ln_record's subscription")


def pypi_mcap() -> Any:
    """The PyPI `mcap` package (the reference Python reader); buildtree.missing_test_tool
    says what happens where it is not installed."""
    try:
        import mcap.reader  # noqa: F401
        import mcap.stream_reader  # noqa: F401
    except ImportError:
        missing_test_tool("the PyPI package mcap (requirements-dev.txt)")
    import mcap

    return mcap


def pypi_stream(path: Path) -> tuple[list[Any], bool]:
    """Every record the PyPI stream reader (CRCs checked) reads from `path` and whether it
    got to the end: a file without footer ends with EndOfFile after its last record."""
    mcap = pypi_mcap()
    from mcap.exceptions import EndOfFile
    from mcap.stream_reader import StreamReader

    records: list[Any] = []
    try:
        for record in StreamReader(str(path), validate_crcs=True).records:
            records.append(record)
    except EndOfFile:
        return records, False
    assert mcap is not None
    return records, True


def pypi_messages(path: Path) -> list[tuple[str, int, int, bytes]]:
    """(topic, sequence, publish time, data) of every message, by the PyPI stream reader."""
    pypi_mcap()
    from mcap.records import Channel, Message

    records, _ = pypi_stream(path)
    topics = {r.id: r.topic for r in records if isinstance(r, Channel)}
    return [(topics[r.channel_id], r.sequence, r.publish_time, bytes(r.data))
            for r in records if isinstance(r, Message)]
