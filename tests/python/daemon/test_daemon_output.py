"""Output capture: lines arrive one by one while the process runs (pty and pipes, stdout
and stderr apart), a partial line is not held back for ever, the daemon keeps only the
last max_output_lines, and the output log rotates at its size limit keeping N files."""

from __future__ import annotations

import asyncio
import os
import sys
from pathlib import Path

import pytest
from daemonproc import WAIT, Daemon, exited, line, next_event, spec

from links_and_nodes.manager.processes import daemon_wire as dw

PY = sys.executable

# Prints a line, then waits until the file named by argv[1] exists before the next one: a
# line can only arrive before the file is made if it is streamed as it comes.
STEPPER = """
import os, sys, time
for i in range(3):
    print(f"step {i}", flush=True)
    while not os.path.exists(f"{sys.argv[1]}.{i}"):
        time.sleep(0.01)
print("done", flush=True)
"""


def stepper(daemon: Daemon, tmp_path: Path, use_pty: bool) -> tuple[list[str], list[str]]:
    script = tmp_path / "stepper.py"
    script.write_text(STEPPER)
    gate = tmp_path / "gate"

    async def main() -> tuple[list[str], list[str]]:
        async with await daemon.connect() as client:
            await client.spawn(spec("st", f"{PY} {script} {gate}", shell=False, use_pty=use_pty))
            streams = []
            for i in range(3):
                got = await line(client, "st", f"step {i}")
                streams.append(got.stream)
                # The process is blocked until we open the gate: it still runs.
                assert [p.state for p in await client.list()] == ["running"]
                Path(f"{gate}.{i}").touch()
            lines: list[str] = []
            ex = await exited(client, "st", lines)
            assert ex.exit_code == 0
            return streams, lines

    return asyncio.run(main())


def test_lines_stream_as_they_come_pty(daemon: Daemon, tmp_path: Path) -> None:
    streams, rest = stepper(daemon, tmp_path, use_pty=True)
    assert streams == ["pty"] * 3
    assert rest == ["done"]


def test_lines_stream_as_they_come_pipes(daemon: Daemon, tmp_path: Path) -> None:
    streams, rest = stepper(daemon, tmp_path, use_pty=False)
    assert streams == ["stdout"] * 3
    assert rest == ["done"]


def test_pty_and_pipes(daemon: Daemon) -> None:
    code = ("import os, sys; print(os.isatty(1), os.isatty(2), flush=True); "
            "print('to stderr', file=sys.stderr)")

    async def main() -> None:
        async with await daemon.connect() as client:
            await client.spawn(spec("pty", f"{PY} -c \"{code}\""))
            seen: list[object] = []
            await next_event(client, lambda e: isinstance(e, dw.Exited), "exit", seen)
            assert [(e.stream, e.text) for e in seen if isinstance(e, dw.OutputLine)] == \
                [("pty", "True True"), ("pty", "to stderr")]

            await client.spawn(spec("pipes", f"{PY} -c \"{code}\"", use_pty=False))
            seen = []
            await next_event(client, lambda e: isinstance(e, dw.Exited), "exit", seen)
            assert sorted((e.stream, e.text) for e in seen if isinstance(e, dw.OutputLine)) == \
                [("stderr", "to stderr"), ("stdout", "False False")]

    asyncio.run(main())


def test_partial_line_is_flushed_while_running_and_at_exit(daemon: Daemon) -> None:
    async def main() -> None:
        async with await daemon.connect() as client:
            await client.spawn(spec("partial", "printf 'no newline yet'; exec sleep 60"))
            got = await line(client, "partial", "no newline yet")
            assert got.stream == "pty"
            assert [p.state for p in await client.list()] == ["running"]
            await client.stop("partial")
            await exited(client, "partial")

            await client.spawn(spec("tail", "printf 'a\\nb'", use_pty=False))
            lines: list[str] = []
            await exited(client, "tail", lines)
            assert lines == ["a", "b"]

    asyncio.run(main())


def test_bounded_buffer(daemon: Daemon) -> None:
    async def main() -> None:
        async with await daemon.connect() as client:
            await client.spawn(spec("many", "for i in $(seq 1 20); do echo line $i; done",
                                    max_output_lines=5))
            await exited(client, "many")
            kept = await client.output("many", 100)
            assert [x.text for x in kept] == [f"line {i}" for i in range(16, 21)]
            assert all(x.name == "many" and x.stream == "pty" for x in kept)
            assert [x.text for x in await client.output("many", 2)] == ["line 19", "line 20"]
            (info,) = await client.list()
            assert (info.output_lines, info.output_total) == (5, 20)

            await client.spawn(spec("none", "echo hidden", max_output_lines=0))
            await exited(client, "none")
            assert await client.output("none") == []

    asyncio.run(main())


def test_output_log_rotation(daemon: Daemon, tmp_path: Path) -> None:
    log = tmp_path / "out.log"
    # 60 lines of 10 bytes ("line NNNN\n"), at most 100 bytes per file, 2 rotated files kept.
    command = "for i in $(seq 1000 1059); do echo line $i; done"

    async def main() -> None:
        async with await daemon.connect() as client:
            await client.spawn(spec("log", command, output_log=(str(log), 100, 2)))
            await exited(client, "log")

    asyncio.run(main())
    files = [Path(f"{log}.2"), Path(f"{log}.1"), log]  # oldest first
    assert not Path(f"{log}.3").exists()
    texts = [f.read_text() for f in files]
    assert all(len(t) <= 100 for t in texts)
    assert [len(t) for t in texts[:2]] == [100, 100]
    # The kept files are the end of the output, contiguous and in order.
    expected = "".join(f"line {i}\n" for i in range(1000, 1060))
    assert expected.endswith("".join(texts))
    assert texts[-1].endswith("line 1059\n")


def test_output_log_without_limit_appends(daemon: Daemon, tmp_path: Path) -> None:
    log = tmp_path / "plain.log"
    log.write_text("old\n")

    async def main() -> None:
        async with await daemon.connect() as client:
            await client.spawn(spec("plain", "echo one; echo two >&2", use_pty=False,
                                    output_log=(str(log), 0, 0)))
            await exited(client, "plain")

    asyncio.run(main())
    assert log.read_text().splitlines()[0] == "old"
    assert sorted(log.read_text().splitlines()[1:]) == ["one", "two"]


def test_output_log_must_be_a_regular_file(daemon: Daemon, tmp_path: Path) -> None:
    # A FIFO nobody reads would block the daemon's one poll loop in open() (and one that is
    # read, in write()); a device would be renamed by the rotation.  Both are refused.
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)

    async def main() -> None:
        async with await daemon.connect() as client:
            for path in (str(fifo), "/dev/null"):
                with pytest.raises(dw.DaemonError) as refused:
                    await asyncio.wait_for(
                        client.spawn(spec("f", "echo hi", output_log=(path, 10, 1))), WAIT)
                assert refused.value.code == dw.ErrorCode.SPAWN_FAILED
                assert str(refused.value) == f"output log '{path}' is not a regular file"
            assert await client.list() == []
            await client.ping()

    asyncio.run(main())
    assert Path("/dev/null").exists() and not Path("/dev/null").is_file()
