"""RESOURCES and EV_RESOURCES (docs/daemon.md, "Resource samples"): samples of the host and of
the instance's running processes at the asked period, only for the connection that asked and
only with its instance's processes; a negative period stops them; `--resource-period 0`
refuses them.  Bounds are broad: the machine is shared, no figure is timed."""

from __future__ import annotations

import asyncio
import subprocess
import sys
import uuid
from collections.abc import Callable
from pathlib import Path

import pytest
from daemonproc import Daemon, next_event, spec

from links_and_nodes.manager.processes import daemon_client as dc
from links_and_nodes.manager.processes import daemon_wire as dw
from links_and_nodes.manager.processes.daemon_launch import daemon_executable
from links_and_nodes.manager.processes.daemon_resources import ResourceSample

BUSY = f"{sys.executable} -c 'while True: pass'"


def is_sample(event: object) -> bool:
    return isinstance(event, ResourceSample)


def drain(client: dc.DaemonClient) -> list[object]:
    """The events queued so far."""
    queue, out = client.events(), []
    while not queue.empty():
        out.append(queue.get_nowait())
    return out


def test_samples_of_host_and_processes(daemon: Daemon) -> None:
    async def main() -> None:
        async with await daemon.connect() as client, \
                await daemon.connect(f"other-{uuid.uuid4().hex[:8]}") as other:
            await client.spawn(spec("busy", BUSY, shell=False))
            await other.spawn(spec("sleeper", "sleep 60", shell=False))
            await client.resources(0.2)
            first = await next_event(client, is_sample, "a first sample")
            assert isinstance(first, ResourceSample)
            assert [p.name for p in first.processes] == ["busy"]  # not the other instance's
            busy = 0.0
            for _ in range(50):  # some sample shows the busy loop at more than half a core
                sample = await next_event(client, is_sample, "a sample")
                assert isinstance(sample, ResourceSample)
                (p,) = sample.processes
                assert p.rss > 0 and p.threads >= 1 and p.fds >= 1
                busy = max(busy, p.cpu or 0.0)
                if busy > 50:
                    break
            assert busy > 50
            host = sample.host
            assert host.cpus and all(0 <= c <= 100 for c in host.cpus)
            assert 0 < host.mem_available <= host.mem_total
            assert host.swap_free <= host.swap_total
            assert any(n.interface == "lo" and n.rx >= 0 for n in host.nets)
            assert not any(map(is_sample, drain(other)))  # the other connection did not ask
            await client.resources(-1)  # stop
            drain(client)
            await client.ping()  # every sample sent before the stop has come by now
            drain(client)
            await asyncio.sleep(0.6)  # three periods
            assert not any(map(is_sample, drain(client)))
            await client.stop("busy")
            await other.stop("sleeper")

    asyncio.run(main())


def test_sampling_disabled(start: Callable[..., Daemon]) -> None:
    daemon = start("--resource-period", "0")

    async def main() -> None:
        async with await daemon.connect() as client:
            with pytest.raises(dw.DaemonError) as err:
                await client.resources()
            assert err.value.code == dw.ErrorCode.LIMIT
            assert "--resource-period 0" in str(err.value)
            await client.ping()  # the connection stays

    asyncio.run(main())


def test_bad_period_option(tmp_path: Path) -> None:
    for bad in ("0.01", "5000", "-1", "x", "1s"):
        out = subprocess.run([str(daemon_executable()), "--key-file", str(tmp_path / "k"),
                              "--resource-period", bad], capture_output=True, text=True,
                             timeout=30)
        assert out.returncode == 2
        assert "--resource-period needs seconds 0.1..3600, or 0" in out.stderr
