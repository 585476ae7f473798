"""An ln_daemon in a lab host answers a daemon client running on another lab host (the
manager's), starts processes in its own host, and can be killed and restarted."""

from __future__ import annotations

import os
import sys
import uuid
from pathlib import Path

from netlab import DaemonProc, Host, NetLab

REPO = Path(__file__).resolve().parents[3]

# Connect to a daemon, ping it, let it run a shell command and print the command's output.
CLIENT = """
import asyncio, sys
from links_and_nodes.manager.processes import daemon_client as dc
from links_and_nodes.manager.processes import daemon_keys as dk
from links_and_nodes.manager.processes import daemon_wire as dw

async def main(host, port, key_file, command):
    client = await dc.DaemonClient.connect(host, int(port), dk.read_key_file(key_file),
                                           "netlab-test")
    await client.ping()
    print("pong", flush=True)
    await client.spawn(dw.SpawnSpec(name="where", command=command, shell=True,
                                    env={"PATH": "/usr/bin:/bin"}, use_pty=False))
    events = client.events()
    while (event := await events.get()) is not None:
        if isinstance(event, dw.OutputLine):
            print(event.text, flush=True)
        elif isinstance(event, dw.Exited):
            print("exit", event.exit_code, flush=True)
            break
    await client.close()

asyncio.run(main(*sys.argv[1:]))
"""


def run_client(on: Host, daemon: DaemonProc, command: str = "true") -> list[str]:
    env = {**on.env(), "PYTHONPATH": os.pathsep.join([str(REPO / "python"), str(REPO)])}
    result = on.run([sys.executable, "-c", CLIENT, daemon.host.address, str(daemon.port),
                     str(daemon.key_file), command], env=env)
    assert result.returncode == 0, result.stderr
    return result.stdout.splitlines()


def test_daemon_answers_a_client_on_the_manager_host(netlab: NetLab) -> None:
    a, mgr = netlab["a"], netlab.add_host("mgr")
    marker = f"netlab-{uuid.uuid4().hex}"
    a.run(["touch", f"/dev/shm/{marker}"], check=True)
    daemon = a.start_daemon()
    assert daemon.address == f"{a.address}:54376"
    assert daemon.pid in a.pids()
    lines = run_client(mgr, daemon, "cat /proc/sys/kernel/hostname; ls /dev/shm")
    # The daemon's process runs in host a: a's hostname and a's /dev/shm, not mgr's.
    assert lines == ["pong", a.host_id, marker, "exit 0"]


def test_daemon_kill_and_restart(netlab: NetLab) -> None:
    a, b = netlab["a"], netlab["b"]
    daemon = a.start_daemon(port=0)
    assert daemon.port != 0 and b.daemon_answers(a.address, daemon.port)
    first = daemon.pid
    assert daemon.kill() == -9
    assert not b.daemon_answers(a.address, daemon.port)
    daemon.restart()
    assert daemon.pid != first and b.daemon_answers(a.address, daemon.port)
    assert run_client(b, daemon) == ["pong", "exit 0"]
    assert daemon.terminate() == 0
    assert daemon.log_path.read_text().count("ln_daemon: listening on") == 2


def test_daemons_of_two_hosts_share_the_default_port(netlab: NetLab) -> None:
    a, b = netlab["a"], netlab["b"]
    da, db = a.start_daemon(), b.start_daemon()
    assert da.port == db.port == 54376
    assert run_client(b, da) == ["pong", "exit 0"] and run_client(a, db) == ["pong", "exit 0"]
