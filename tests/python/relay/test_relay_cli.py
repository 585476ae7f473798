"""The `ln_relay` command: bad arguments and unusable addresses give one clear error line;
a real process with --ready-file relays UDP and TCP, and on SIGTERM prints its stats,
writes them to --stats-file and exits 0."""

from __future__ import annotations

import asyncio
import json
import os
import re
import signal
import socket
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from links_and_nodes.relay import cli

from .conftest import WAIT, UdpPeer, until

REPO = Path(__file__).resolve().parents[3]


@pytest.mark.parametrize(("args", "message"), [
    ([], "nothing to relay: give at least one --udp LISTEN TARGET or --tcp LISTEN TARGET"),
    (["--udp", "127.0.0.1:0"], "argument --udp: expected 2 arguments"),
    (["--udp", "127.0.0.1", "127.0.0.1:9"],
     "argument --udp: bad address '127.0.0.1': expected HOST:PORT or [V6HOST]:PORT"),
    (["--tcp", "127.0.0.1:0", "127.0.0.1:0"],
     "argument --tcp: bad address '127.0.0.1:0': the port must be a number 1..65535"),
    (["--udp", "::1:5000", "127.0.0.1:9"],
     "argument --udp: bad address '::1:5000': an IPv6 address needs brackets, "
     "e.g. [::1]:5000"),
    (["--udp", "a:1", "b:2", "--loss", "1.2"],
     "argument --loss: '1.2' is not a probability in 0..1"),
    (["--udp", "a:1", "b:2", "--duplicate", "x"],
     "argument --duplicate: 'x' is not a probability in 0..1"),
    (["--udp", "a:1", "b:2", "--delay-ms", "-5"],
     "argument --delay-ms: '-5' is not a number of milliseconds >= 0"),
    (["--udp", "a:1", "b:2", "--jitter-ms", "inf"],
     "argument --jitter-ms: 'inf' is not a number of milliseconds >= 0"),
    (["--udp", "a:1", "b:2", "--rto-ms", "0"],
     "argument --rto-ms: '0' is not a number of milliseconds > 0"),
    (["--tcp", "a:1", "b:2", "--rto-ms", "500", "--rto-max-ms", "100"],
     "--rto-max-ms (100) must be at least --rto-ms (500)"),
    (["--udp", "a:1", "b:2", "--seed", "-1"], "argument --seed: '-1' is not an integer >= 0"),
    (["--udp", "a:1", "b:2", "--queue-limit", "0"],
     "argument --queue-limit: '0' is not an integer > 0"),
])
def test_bad_arguments(args: list[str], message: str,
                       capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        cli.main(args)
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert err.splitlines()[-1] == f"ln_relay: error: {message}", err


def test_an_address_in_use_is_an_error(capsys: pytest.CaptureFixture[str]) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        status = cli.main(["--udp", "127.0.0.1:0", "127.0.0.1:9",
                           "--tcp", f"127.0.0.1:{port}", "127.0.0.1:9"])
    assert status == 1
    assert capsys.readouterr().err == (f"ln_relay: error: tcp 127.0.0.1:{port} -> "
                                       f"127.0.0.1:9: cannot listen on 127.0.0.1:{port}: "
                                       "Address already in use\n")


def test_tcp_only_faults_are_noted(capsys: pytest.CaptureFixture[str]) -> None:
    with socket.socket() as taken:  # so that the run stops right after the note
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        listen = f"127.0.0.1:{taken.getsockname()[1]}"
        assert cli.main(["--tcp", listen, "127.0.0.1:9", "--reorder", "0.1"]) == 1
    assert capsys.readouterr().err.startswith(
        "ln_relay: note: --duplicate and --reorder do not apply to TCP links\n")


async def test_the_command_relays_and_reports_on_sigterm(
        tmp_path: Path, udp_peers: Callable[..., UdpPeer]) -> None:
    echo, client = udp_peers(echo=True), udp_peers()

    async def tcp_echo(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        while data := await reader.read(1 << 16):
            writer.write(data)
            await writer.drain()
        writer.close()

    server = await asyncio.start_server(tcp_echo, "127.0.0.1", 0)
    tcp_target = server.sockets[0].getsockname()
    ready, stats_file = tmp_path / "ready.json", tmp_path / "stats.json"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(REPO / "python"), *filter(None, [os.environ.get("PYTHONPATH")])]))
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "links_and_nodes.relay.cli",
        "--udp", "127.0.0.1:0", f"127.0.0.1:{echo.addr[1]}",
        "--tcp", "127.0.0.1:0", f"127.0.0.1:{tcp_target[1]}",
        "--delay-ms", "1", "--seed", "42", "--ready-file", str(ready),
        "--stats-file", str(stats_file),
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE, env=env, cwd=REPO)
    try:
        await until(ready.exists, "the ready file")
        info = json.loads(ready.read_text())
        assert info["pid"] == proc.pid and info["seed"] == 42
        udp, tcp = info["links"]
        assert (udp["proto"], tcp["proto"]) == ("udp", "tcp")
        assert udp["target"] == f"127.0.0.1:{echo.addr[1]}"
        assert udp["port"] > 0 and udp["listen"] == f"127.0.0.1:{udp['port']}"
        assert proc.stdout is not None
        line = (await asyncio.wait_for(proc.stdout.readline(), WAIT)).decode()
        assert re.fullmatch(rf"ln_relay: listening on udp 127\.0\.0\.1:{udp['port']} -> "
                            rf"127\.0\.0\.1:{echo.addr[1]}, tcp 127\.0\.0\.1:{tcp['port']} "
                            rf"-> 127\.0\.0\.1:{tcp_target[1]} \(seed 42, pid {proc.pid}\)\n",
                            line), line

        for i in range(20):
            client.send(b"ping %d" % i, ("127.0.0.1", udp["port"]))
            await until(lambda n=i + 1: len(client.received) == n, f"pong {i}")
        reader, writer = await asyncio.open_connection("127.0.0.1", tcp["port"])
        writer.write(b"t" * 300_000)
        writer.write_eof()
        assert await asyncio.wait_for(reader.read(), WAIT) == b"t" * 300_000
        writer.close()

        proc.send_signal(signal.SIGTERM)
        out, err = await asyncio.wait_for(proc.communicate(), WAIT)
    finally:
        if proc.returncode is None:
            proc.kill()
            await proc.wait()
        server.close()
    assert proc.returncode == 0, err.decode()
    assert err == b""
    report = json.loads(stats_file.read_text())
    assert report["seed"] == 42 and report["faults"]["delay_ms"] == 1.0
    udp_stats, tcp_stats = report["links"]
    assert udp_stats["clients"] == 1
    assert udp_stats["upstream"]["datagrams_in"] == udp_stats["upstream"]["datagrams_out"] == 20
    assert udp_stats["downstream"]["datagrams_out"] == 20
    assert tcp_stats["connections"] == 1 and tcp_stats["active_connections"] == 0
    assert tcp_stats["upstream"]["bytes_out"] == tcp_stats["downstream"]["bytes_out"] == 300_000
    assert tcp_stats["upstream"]["duplicated"] is None
    lines = out.decode().splitlines()
    assert lines[0] == f"ln_relay: udp 127.0.0.1:{udp['port']} -> 127.0.0.1:{echo.addr[1]}: " \
                       "1 client"
    assert lines[1].startswith("ln_relay:   upstream: 20 datagrams in, 20 out, 0 lost")
    assert lines[3].startswith(f"ln_relay: tcp 127.0.0.1:{tcp['port']} -> ")
    assert len(lines) == 6
    assert not list(tmp_path.glob(".*.tmp"))
