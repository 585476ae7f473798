"""The daemon outlives its managers: when the manager's connection goes (closed, or the
manager process SIGKILLed), processes keep running, exits meanwhile are kept, and a new
connection of the same instance sees true states and recent output.  Instances sharing
one daemon never see each other's processes or events."""

from __future__ import annotations

import asyncio
import contextlib
import os
import selectors
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from daemonproc import REPO, WAIT, Daemon, alive, descendants, exited, line, spec, wait_for

from links_and_nodes.manager.processes import daemon_wire as dw

# A throw-away "manager": connects, starts two processes, says so, then waits to be killed.
MANAGER = """
import asyncio, sys
from links_and_nodes.manager.processes import daemon_client as dc
from links_and_nodes.manager.processes import daemon_wire as dw
async def main():
    port, key, instance, gate = int(sys.argv[1]), bytes.fromhex(sys.argv[2]), sys.argv[3], sys.argv[4]
    client = await dc.DaemonClient.connect("127.0.0.1", port, key, instance)
    env = {"PATH": "/usr/bin:/bin"}
    await client.spawn(dw.SpawnSpec("long", "echo long-start; exec sleep 600", True, env))
    # "short" ends once the gate file exists, i.e. while nobody is connected.
    await client.spawn(dw.SpawnSpec(
        "short", f"echo short-start; while [ ! -e {gate} ]; do sleep 0.02; done; "
                 "echo short-end; exit 3", True, env))
    started = set()
    while started != {"long", "short"}:
        ev = await client.events().get()
        if getattr(ev, "text", "").endswith("-start"):
            started.add(ev.name)
    print("ready", flush=True)
    await asyncio.sleep(600)
asyncio.run(main())
"""


def check_reattached(daemon: Daemon, long_pid: int) -> None:
    async def main() -> None:
        async with await daemon.connect() as client:
            listed = {p.name: p for p in await client.list()}
            assert listed["long"].state == "running" and listed["long"].pid == long_pid
            assert alive(long_pid)
            short = listed["short"]
            assert (short.state, short.exit_code, short.signal) == ("exited", 3, None)
            assert short.exited is not None
            texts = [x.text for x in await client.output("short")]
            assert texts == ["short-start", "short-end"]
            assert [x.text for x in await client.output("long")] == ["long-start"]
            # The re-attached connection gets the events from now on.
            await client.stop("long")
            ex = await exited(client, "long")
            assert ex.signal == signal.SIGTERM

    asyncio.run(main())


def test_connection_closed_then_reattach(daemon: Daemon, tmp_path: Path) -> None:
    gate = tmp_path / "gate"

    async def first() -> int:
        client = await daemon.connect()
        info = await client.spawn(spec("long", "echo long-start; exec sleep 600"))
        await client.spawn(spec("short", f"echo short-start; while [ ! -e {gate} ]; do "
                                "sleep 0.02; done; echo short-end; exit 3"))
        await line(client, "short", "short-start")
        await client.close()
        return info.pid

    long_pid = asyncio.run(first())
    gate.touch()
    wait_for(lambda: "short (pid" in daemon.log_text() and "exited with code 3"
             in daemon.log_text(), "short to exit while nobody is connected")
    check_reattached(daemon, long_pid)


def test_manager_killed_then_reattach(daemon: Daemon, tmp_path: Path) -> None:
    gate = tmp_path / "gate"
    script = tmp_path / "manager.py"
    script.write_text(MANAGER)
    manager = subprocess.Popen([sys.executable, str(script), str(daemon.port), daemon.key.hex(),
                                daemon.instance, str(gate)], stdout=subprocess.PIPE, text=True,
                               env={"PYTHONPATH": f"{REPO / 'python'}:{REPO}",
                                    "PATH": "/usr/bin:/bin"})
    daemon.extra.append(manager)  # type: ignore[arg-type]
    assert manager.stdout is not None
    with selectors.DefaultSelector() as sel:
        sel.register(manager.stdout, selectors.EVENT_READ)
        assert sel.select(WAIT), "the manager script did not get ready"
    assert manager.stdout.readline().strip() == "ready"
    manager.kill()
    manager.wait()
    manager.stdout.close()
    wait_for(lambda: "closed by the peer" in daemon.log_text(), "the daemon to notice")
    gate.touch()
    wait_for(lambda: "exited with code 3" in daemon.log_text(), "short to exit")

    async def long_pid() -> int:
        async with await daemon.connect() as client:
            return {p.name: p for p in await client.list()}["long"].pid

    check_reattached(daemon, asyncio.run(long_pid()))


def test_instances_are_separate(daemon: Daemon) -> None:
    async def main() -> None:
        a = await daemon.connect("instance-a")
        b = await daemon.connect("instance-b")
        try:
            await a.spawn(spec("same", "echo from-a; exec sleep 600"))
            await line(a, "same", "from-a")
            assert await b.list() == []
            for call in (b.output("same"), b.stop("same"), b.signal("same", 9),
                         b.forget("same")):
                with pytest.raises(dw.DaemonError) as e:
                    await call
                assert e.value.code == dw.ErrorCode.UNKNOWN_PROCESS
            # The same name in the other instance is another process.
            await b.spawn(spec("same", "echo from-b; exec sleep 600"))
            await line(b, "same", "from-b")
            await a.stop("same")
            await exited(a, "same")
            (still,) = await b.list()
            assert still.state == "running"
            # B never saw an event of A.
            await b.stop("same")
            await exited(b, "same")
            events = []
            while not b.events().empty():
                events.append(b.events().get_nowait())
            assert all(getattr(e, "text", "") != "from-a" for e in events)
            assert [p.name for p in await a.list()] == ["same"]
        finally:
            await a.close()
            await b.close()

    asyncio.run(main())


def test_two_connections_of_one_instance_both_get_events(daemon: Daemon) -> None:
    async def main() -> None:
        one = await daemon.connect()
        two = await daemon.connect()
        try:
            await one.spawn(spec("e", "echo hi"))
            for client in (one, two):
                await line(client, "e", "hi")
                await exited(client, "e")
        finally:
            await one.close()
            await two.close()

    asyncio.run(main())


def test_connection_loss_ends_events_and_calls(daemon: Daemon) -> None:
    async def main() -> None:
        client = await daemon.connect()
        await client.spawn(spec("x", "sleep 600"))
        tree = descendants(daemon.proc.pid)
        # A stopped daemon cannot answer: this call is surely pending when it dies.
        daemon.proc.send_signal(signal.SIGSTOP)
        pending = asyncio.create_task(client.list())
        await asyncio.sleep(0.05)
        assert not pending.done()
        daemon.proc.send_signal(signal.SIGKILL)  # the daemon itself goes away
        daemon.proc.wait()
        with pytest.raises(dw.DaemonConnectionError):
            await pending
        for pid in tree:  # nobody supervises them any more
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        queue = client.events()
        while await asyncio.wait_for(queue.get(), 30) is not None:
            pass
        assert client.closed
        with pytest.raises(dw.DaemonConnectionError):
            await client.list()
        with pytest.raises(ConnectionError):
            await client.ping()
        await client.close()

    asyncio.run(main())


def test_close_right_after_connect(daemon: Daemon) -> None:
    """A connection closed before anything came from the daemon (its reader had not run
    yet) still closes, ends its events and refuses further calls."""
    async def main() -> None:
        client = await daemon.connect()
        async with asyncio.timeout(WAIT):  # an upper bound: it used to hang
            await client.close()  # in this task: its reader has not run yet
        assert client.closed
        assert await asyncio.wait_for(client.events().get(), WAIT) is None
        with pytest.raises(dw.DaemonConnectionError):
            await client.ping()

    asyncio.run(main())
