"""Authentication: without the key nothing is done - every command is refused and the
connection closed, before a handshake, with a wrong key or a proof for another instance;
the daemon must prove the key too; after the handshake every frame needs its tag, so an
injected or replayed frame ends the connection."""

from __future__ import annotations

import asyncio
import os
import struct
from pathlib import Path

import pytest
from daemonproc import Daemon, RawConnection, spec

from links_and_nodes.manager.processes import daemon_client as dc
from links_and_nodes.manager.processes import daemon_wire as dw
from links_and_nodes.wire import codec as wc


# One well-formed payload per command; the SPAWN would create a file if it ever ran.
def payloads(marker: Path) -> dict[dw.Msg, bytes]:
    name = wc.encode_str("victim")
    return {
        dw.Msg.SPAWN: dw.encode_spawn(spec("victim", f"touch {marker}")),
        dw.Msg.STOP: name,
        dw.Msg.SIGNAL: name + struct.pack("<iB", 9, 0),
        dw.Msg.LIST: b"",
        dw.Msg.OUTPUT: name + struct.pack("<I", 10),
        dw.Msg.FORGET: name,
        dw.Msg.PING: b"",
    }


def assert_nothing_ran(daemon: Daemon, marker: Path) -> None:
    async def main() -> None:
        async with await daemon.connect() as client:
            assert await client.list() == []

    asyncio.run(main())
    assert not marker.exists()


def test_wrong_key_is_refused_at_connect(daemon: Daemon) -> None:
    async def main() -> None:
        with pytest.raises(dw.DaemonAuthError) as e:
            await daemon.connect(key=os.urandom(32))
        assert e.value.code == dw.ErrorCode.AUTH_FAILED
        assert "authentication failed" in str(e.value)

    asyncio.run(main())
    assert "authentication failed (wrong key)" in daemon.log_text()


def test_wrong_key_refuses_every_command(daemon: Daemon, tmp_path: Path) -> None:
    marker = tmp_path / "ran"
    for mtype, payload in payloads(marker).items():
        conn = RawConnection(daemon.port)
        try:
            hello = conn.client_hello(os.urandom(32), daemon.instance, conn.hello())
            # The command follows the hello at once, as a client that does not wait would.
            conn.send(hello + conn.frame(mtype, 1, payload, tagged=False))
            code, text = conn.expect_error_and_close()
            assert code == dw.ErrorCode.AUTH_FAILED, (mtype, text)
        finally:
            conn.close()
    assert_nothing_ran(daemon, marker)


def test_unauthenticated_commands_are_refused(daemon: Daemon, tmp_path: Path) -> None:
    marker = tmp_path / "ran"
    for mtype, payload in payloads(marker).items():
        conn = RawConnection(daemon.port)
        try:
            conn.hello()
            conn.send(conn.frame(mtype, 1, payload, tagged=False))
            code, text = conn.expect_error_and_close()
            assert code == dw.ErrorCode.NOT_AUTHENTICATED, (mtype, text)
            assert text.startswith("not authenticated")
        finally:
            conn.close()
    assert_nothing_ran(daemon, marker)


def test_proof_is_bound_to_the_instance(daemon: Daemon) -> None:
    conn = RawConnection(daemon.port)
    try:
        nonce = conn.hello()
        # A proof computed for instance "a" but presented as instance "b".
        good = conn.client_hello(daemon.key, "a", nonce)
        forged = good.replace(wc.encode_str("a"), wc.encode_str("b"))
        forged = struct.pack("<I", len(forged) - 4) + forged[4:]
        conn.send(forged)
        code, _ = conn.expect_error_and_close()
        assert code == dw.ErrorCode.AUTH_FAILED
    finally:
        conn.close()


def test_old_hello_cannot_be_replayed(daemon: Daemon) -> None:
    # A recorded, valid CLIENT_HELLO is useless on a new connection: new daemon nonce.
    first = RawConnection(daemon.port)
    recorded = first.client_hello(daemon.key, daemon.instance, first.hello())
    first.send(recorded)
    assert first.read_frame()[0] == dw.Msg.AUTH_OK
    first.close()
    second = RawConnection(daemon.port)
    try:
        second.hello()
        second.send(recorded)
        code, _ = second.expect_error_and_close()
        assert code == dw.ErrorCode.AUTH_FAILED
    finally:
        second.close()


def test_daemon_must_prove_the_key() -> None:
    # A fake daemon without the key: it cannot produce the proof, the client refuses it.
    async def fake(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        hello = dw.MAGIC + struct.pack("<H", dw.PROTOCOL_VERSION) + os.urandom(32)
        writer.write(struct.pack("<IBI", 5 + len(hello), dw.Msg.DAEMON_HELLO, 0) + hello)
        (length,) = struct.unpack("<I", await reader.readexactly(4))
        await reader.readexactly(length)
        writer.write(struct.pack("<IBI", 5 + 32, dw.Msg.AUTH_OK, 0) + os.urandom(32))
        await writer.drain()
        await reader.read()

    async def main() -> None:
        server = await asyncio.start_server(fake, "127.0.0.1", 0)
        port = server.sockets[0].getsockname()[1]
        async with server:
            with pytest.raises(dw.DaemonAuthError) as e:
                await dc.DaemonClient.connect("127.0.0.1", port, os.urandom(32), "x")
            assert "could not prove" in str(e.value)

    asyncio.run(main())


def test_frames_need_their_tag(daemon: Daemon, tmp_path: Path) -> None:
    marker = tmp_path / "ran"
    spawn = payloads(marker)[dw.Msg.SPAWN]
    cases = {
        "untagged": lambda c: c.frame(dw.Msg.SPAWN, 1, spawn + b"\0" * 32, tagged=False),
        "wrong key": lambda c: _with_key(c, os.urandom(32), spawn),
        "replayed": lambda c: _replayed(c),
        "altered": lambda c: _altered(c, spawn),
    }
    for what, make in cases.items():
        conn = RawConnection(daemon.port)
        try:
            conn.authenticate(daemon.key, daemon.instance)
            conn.send(make(conn))
            code, text = conn.expect_error_and_close()
            assert code == dw.ErrorCode.BAD_REQUEST, what
            assert "wrong tag" in text, (what, text)
        finally:
            conn.close()
    assert_nothing_ran(daemon, marker)


def _with_key(conn: RawConnection, key: bytes, payload: bytes) -> bytes:
    assert conn.keys is not None
    saved = conn.keys
    conn.keys = {**saved, "to_daemon": key}
    try:
        return conn.frame(dw.Msg.SPAWN, 1, payload)
    finally:
        conn.keys = saved


def _replayed(conn: RawConnection) -> bytes:
    ping = conn.frame(dw.Msg.PING, 1, b"")
    conn.send(ping)
    assert conn.read_frame()[0] == dw.Msg.OK
    return ping  # the same bytes again: sequence number 0 is used up


def _altered(conn: RawConnection, payload: bytes) -> bytes:
    frame = bytearray(conn.frame(dw.Msg.SPAWN, 1, payload))
    frame[20] ^= 0x01
    return bytes(frame)


def test_version_mismatch_is_refused(daemon: Daemon) -> None:
    conn = RawConnection(daemon.port)
    try:
        hello = bytearray(conn.client_hello(daemon.key, daemon.instance, conn.hello()))
        struct.pack_into("<H", hello, 4 + 5 + 8, 99)
        conn.send(bytes(hello))
        code, text = conn.expect_error_and_close()
        assert code == dw.ErrorCode.VERSION
        assert text == ("unsupported protocol version 99; this daemon speaks version "
                        f"{dw.PROTOCOL_VERSION}")
    finally:
        conn.close()
