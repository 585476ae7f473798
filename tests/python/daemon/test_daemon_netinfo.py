"""NET_INFO and the host id: the daemon reports libln's host id ($LN_HOST_ID, else
hostname/boot_id) and the data port it advertises, and every process it starts gets
LN_HOST_ID unless its environment sets one."""

from __future__ import annotations

import asyncio
import socket
import uuid
from collections.abc import Callable
from pathlib import Path

from daemonproc import Daemon, exited, spec

from links_and_nodes.manager.processes import daemon_wire as dw


def net_info(daemon: Daemon) -> dw.NetInfo:
    async def main() -> dw.NetInfo:
        async with await daemon.connect() as client:
            return await client.net_info()

    return asyncio.run(main())


def test_host_id_from_the_environment(start: Callable[..., Daemon]) -> None:
    host_id = f"robot-{uuid.uuid4().hex[:8]}"
    daemon = start(env={"LN_HOST_ID": host_id})
    assert net_info(daemon) == dw.NetInfo(host_id=host_id, data_port=daemon.data_port)
    assert f"host id {host_id}" in daemon.log_text()


def test_host_id_of_the_host(start: Callable[..., Daemon]) -> None:
    daemon = start(env={"LN_HOST_ID": ""})  # empty counts as unset
    boot_id = Path("/proc/sys/kernel/random/boot_id").read_text().strip()
    assert net_info(daemon).host_id == f"{socket.gethostname()}/{boot_id}"


def test_advertised_data_port(start: Callable[..., Daemon]) -> None:
    daemon = start("--advertise-data-port", "40123")
    info = net_info(daemon)
    assert info.data_port == 40123
    assert f"data port {daemon.data_port} (advertised 40123)" in daemon.log_text()


def test_spawned_processes_get_the_host_id(start: Callable[..., Daemon]) -> None:
    host_id = f"robot-{uuid.uuid4().hex[:8]}"
    daemon = start(env={"LN_HOST_ID": host_id})

    async def main() -> tuple[list[str], list[str]]:
        async with await daemon.connect() as client:
            inherited: list[str] = []
            await client.spawn(spec("plain", "echo id=$LN_HOST_ID"))
            await exited(client, "plain", inherited)
            own: list[str] = []
            s = spec("own", "echo id=$LN_HOST_ID")
            s.env["LN_HOST_ID"] = "chosen"
            await client.spawn(s)
            await exited(client, "own", own)
            return inherited, own

    inherited, own = asyncio.run(main())
    assert inherited == [f"id={host_id}"]
    assert own == ["id=chosen"]
