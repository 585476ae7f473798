"""Stopping and exits: the term signal goes to the process group, SIGKILL to the whole tree
after the term timeout, grandchildren die too (also ones that called setsid and were
orphaned), exit codes and signals are reported, SIGNAL reaches the process."""

from __future__ import annotations

import asyncio
import os
import signal
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from daemonproc import (
    Daemon,
    alive,
    descendants,
    exited,
    line,
    next_event,
    proc_stat,
    spec,
    wait_for,
)

from links_and_nodes.manager.processes import daemon_wire as dw

PY = sys.executable


def test_stop_with_custom_term_signal(daemon: Daemon) -> None:
    # The handler writes with os.write: the signal may come while print() is still busy.
    code = ("import os, signal, sys, time\n"
            "def on(sig, frame):\n"
            "    os.write(1, b'got %d\\n' % sig); sys.exit(7)\n"
            "signal.signal(signal.SIGINT, on)\n"
            "signal.signal(signal.SIGTERM, lambda *a: sys.exit(99))\n"
            "print('ready', flush=True)\n"
            "while True: time.sleep(1)\n")

    async def main() -> None:
        async with await daemon.connect() as client:
            await client.spawn(spec("int", f"{PY} -c \"{code}\"", shell=False,
                                    term_signal=signal.SIGINT))
            await line(client, "int", "ready")
            await client.stop("int")
            lines: list[str] = []
            ex = await exited(client, "int", lines)
            assert lines == ["got 2"], lines
            assert (ex.exit_code, ex.signal) == (7, None)

    asyncio.run(main())


def test_sigkill_after_term_timeout(daemon: Daemon) -> None:
    code = ("import signal, time; signal.signal(signal.SIGTERM, signal.SIG_IGN); "
            "print('ready', flush=True); time.sleep(600)")

    async def main() -> None:
        async with await daemon.connect() as client:
            info = await client.spawn(spec("stubborn", f"{PY} -c \"{code}\"", shell=False,
                                           term_timeout=0.3))
            await line(client, "stubborn", "ready")
            await client.stop("stubborn")
            listed = {p.name: p for p in await client.list()}
            assert listed["stubborn"].state in ("stopping", "exited")
            ex = await exited(client, "stubborn")
            assert (ex.exit_code, ex.signal, ex.pid) == (None, signal.SIGKILL, info.pid)
            (info,) = await client.list()
            assert (info.state, info.signal) == ("exited", signal.SIGKILL)

    asyncio.run(main())
    assert "SIGKILL to its tree" in daemon.log_text()


# Builds a tree: a child in the same process group, a child that called setsid, and a
# grandchild of that one which is orphaned (its parent exits) - re-parented away from the
# tree's main process.  All ignore SIGTERM; each writes "pid starttime sid" to argv[1].
TREE = r"""
import os, signal, sys, time
out = sys.argv[1]
def record(tag):
    st = open(f"/proc/{os.getpid()}/stat").read()
    fields = st[st.rindex(")") + 2:].split()
    with open(f"{out}.{tag}", "w") as f:
        f.write(f"{os.getpid()} {fields[19]} {os.getsid(0)}")
signal.signal(signal.SIGTERM, signal.SIG_IGN)
if os.fork() == 0:
    record("child")
    time.sleep(600)
    os._exit(0)
if os.fork() == 0:
    os.setsid()
    if os.fork() == 0:
        record("orphan")
        time.sleep(600)
        os._exit(0)
    record("setsid")
    time.sleep(0.2)
    os._exit(0)      # leaves the orphan behind
record("main")
print("ready", flush=True)
while True:
    time.sleep(1)
"""


def read_tree(out: Path) -> dict[str, tuple[int, int, int]]:
    tags = ("main", "child", "setsid", "orphan")
    wait_for(lambda: all(Path(f"{out}.{t}").exists() and Path(f"{out}.{t}").read_text()
                         for t in tags), "the tree to record itself")
    return {t: tuple(int(x) for x in Path(f"{out}.{t}").read_text().split())  # type: ignore
            for t in tags}


def test_stop_kills_the_whole_tree(daemon: Daemon, tmp_path: Path) -> None:
    script = tmp_path / "tree.py"
    script.write_text(TREE)
    out = tmp_path / "pids"

    async def main() -> dict[str, tuple[int, int, int]]:
        async with await daemon.connect() as client:
            info = await client.spawn(spec("tree", f"{PY} {script} {out}", shell=False,
                                           term_timeout=0.5))
            await line(client, "tree", "ready")
            tree = await asyncio.to_thread(read_tree, out)
            assert tree["main"][0] == info.pid
            # The orphan really left: other session, and its parent is gone.
            wait_for(lambda: not alive(tree["setsid"][0], tree["setsid"][1]),
                     "the setsid'd child to exit")
            orphan = proc_stat(tree["orphan"][0])
            assert orphan is not None and orphan[3] != info.pid
            assert alive(tree["child"][0], tree["child"][1])
            await client.stop("tree")
            ex = await exited(client, "tree")
            assert ex.signal == signal.SIGKILL  # it ignored SIGTERM
            # Exited means the tree is gone: nothing of it may be alive now.
            for tag, (pid, start, _) in tree.items():
                assert not alive(pid, start), f"{tag} (pid {pid}) survived the stop"
            return tree

    asyncio.run(main())


def test_leftovers_of_a_natural_exit_are_ended(daemon: Daemon, tmp_path: Path) -> None:
    # The main process exits by itself and leaves a background child: the record stays
    # "stopping" until that child is gone too, then the main's exit code is reported.
    pidfile = tmp_path / "bg"

    async def main() -> None:
        async with await daemon.connect() as client:
            await client.spawn(spec("bg", f"sleep 600 & echo $! > {pidfile}; exit 4",
                                    use_pty=False))
            ex = await exited(client, "bg")
            assert (ex.exit_code, ex.signal) == (4, None)
            pid = int(pidfile.read_text())
            assert not alive(pid)

    asyncio.run(main())


@pytest.mark.parametrize("command, shell, code, sig", [
    ("exit 0", True, 0, None),
    ("exit 42", True, 42, None),
    (f"{PY} -c 'import os, signal; os.kill(os.getpid(), signal.SIGUSR1)'", False, None,
     signal.SIGUSR1),
    ("kill -SEGV $$", True, None, signal.SIGSEGV),
])
def test_exit_codes_and_signals(daemon: Daemon, command: str, shell: bool, code: int | None,
                                sig: int | None) -> None:
    async def main() -> None:
        async with await daemon.connect() as client:
            info = await client.spawn(spec("x", command, shell=shell, use_pty=False,
                                           rlimits=[("core", 0, 0)]))
            ex = await exited(client, "x")
            assert (ex.pid, ex.exit_code, ex.signal) == (info.pid, code, sig)
            (listed,) = await client.list()
            assert (listed.state, listed.exit_code, listed.signal) == ("exited", code, sig)
            assert listed.exited is not None and listed.exited >= listed.started

    asyncio.run(main())


def test_signal_command(daemon: Daemon) -> None:
    code = ("import os, signal, time\n"
            "signal.signal(signal.SIGUSR1, lambda *a: os.write(1, b'usr1\\n'))\n"
            "print('ready', flush=True)\n"
            "while True: time.sleep(1)\n")

    async def main() -> None:
        async with await daemon.connect() as client:
            await client.spawn(spec("sig", f"{PY} -c \"{code}\"", shell=False))
            await line(client, "sig", "ready")
            await client.signal("sig", signal.SIGUSR1)
            await line(client, "sig", "usr1")
            await client.signal("sig", signal.SIGUSR1, group=True)
            await line(client, "sig", "usr1")
            await client.signal("sig", signal.SIGKILL)
            ex = await exited(client, "sig")
            assert ex.signal == signal.SIGKILL
            with pytest.raises(dw.DaemonError) as e:
                await client.signal("sig", signal.SIGUSR1)
            assert e.value.code == dw.ErrorCode.NOT_RUNNING

    asyncio.run(main())


def test_stop_forget_errors(daemon: Daemon) -> None:
    async def main() -> None:
        async with await daemon.connect() as client:
            await client.spawn(spec("f", "sleep 600"))
            with pytest.raises(dw.DaemonError) as e:
                await client.forget("f")
            assert e.value.code == dw.ErrorCode.STILL_RUNNING
            assert str(e.value) == "process f is running; stop it first"
            await client.stop("f")
            await exited(client, "f")
            with pytest.raises(dw.DaemonError) as e:
                await client.stop("f")
            assert e.value.code == dw.ErrorCode.NOT_RUNNING
            await client.forget("f")
            assert await client.list() == []
            for call in (client.stop("nope"), client.forget("nope"), client.output("nope")):
                with pytest.raises(dw.DaemonError) as e:
                    await call
                assert e.value.code == dw.ErrorCode.UNKNOWN_PROCESS

    asyncio.run(main())


def test_state_events(daemon: Daemon) -> None:
    async def main() -> None:
        async with await daemon.connect(state_events=True) as client:
            await client.spawn(spec("st", "sleep 600"))
            await client.stop("st")
            seen: list[object] = []
            await next_event(client, lambda e: isinstance(e, dw.Exited), "exit", seen)
            states = [e.state for e in seen if isinstance(e, dw.StateChanged)]
            assert states == ["running", "stopping", "exited"]

    asyncio.run(main())


@pytest.mark.parametrize("use_pty", [False, True])
def test_killed_daemon_leaves_no_process_behind(start: Callable[..., Daemon],
                                                use_pty: bool) -> None:
    # Without its daemon a tree has nobody to stop it, report it or re-adopt it, so each
    # keeper ends its tree as a STOP would: the term signal, SIGKILL after the term timeout.
    # This tree ignores SIGTERM and SIGHUP (a pty's hang-up does not end it either), with a
    # member in a session of its own, and writes nothing more that could fail.
    daemon = start()

    async def main() -> list[tuple[int, int]]:
        async with await daemon.connect() as client:
            await client.spawn(spec("stubborn", "trap '' TERM HUP; setsid sleep 600 & "
                                    "sleep 600 & echo ready; wait", use_pty=use_pty,
                                    term_timeout=0.5))
            await line(client, "stubborn", "ready")
        return [(pid, st[4]) for pid in descendants(daemon.proc.pid)
                if (st := proc_stat(pid)) is not None]

    tree = asyncio.run(main())
    assert len(tree) == 4  # keeper, shell, two sleeps
    daemon.proc.kill()
    daemon.proc.wait()
    try:
        wait_for(lambda: not any(alive(pid, start) for pid, start in tree),
                 "the tree of the killed daemon to end")
    finally:
        for pid, start_time in tree:
            if alive(pid, start_time):
                os.kill(pid, signal.SIGKILL)
