"""Bad input on the daemon's port - garbage, oversized or malformed frames, connections that
never finish the handshake - closes only that connection; other connections, their events
and the supervised processes carry on."""

from __future__ import annotations

import asyncio
import socket
import struct

from daemonproc import Daemon, RawConnection, alive, line, spec

from links_and_nodes.manager.processes import daemon_wire as dw


def garbage_connections(port: int) -> list[str]:
    """Sends various bad things, each on its own connection; the daemon's replies."""
    results = []
    bad = [
        bytes(range(256)) * 16,                            # noise
        struct.pack("<I", 0xFFFFFFFF) + b"x" * 100,        # absurd length
        struct.pack("<I", (4 << 20) + 1),                  # just over the limit
        struct.pack("<I", 2) + b"ab",                      # too short for a header
        b"GET / HTTP/1.1\r\nHost: x\r\n\r\n",              # the wrong protocol
    ]
    for data in bad:
        conn = RawConnection(port)
        try:
            conn.hello()
            conn.send(data)
            code, text = conn.expect_error_and_close()
            results.append(f"{int(code)} {text}")
        finally:
            conn.close()
    return results


def test_garbage_closes_only_that_connection(daemon: Daemon) -> None:
    async def main() -> None:
        async with await daemon.connect() as client:
            info = await client.spawn(spec("keep", "echo start; while read x; do :; done; "
                                           "sleep 600"))
            await line(client, "keep", "start")
            results = await asyncio.to_thread(garbage_connections, daemon.port)
            assert len(results) == 5
            assert results[1].startswith("1 frame of 4294967295 bytes exceeds the limit")
            assert results[2].startswith(f"1 frame of {(4 << 20) + 1} bytes exceeds")
            assert results[3] == "1 malformed frame of 2 bytes"
            # The authenticated connection and the process are untouched...
            await client.ping()
            (listed,) = await client.list()
            assert listed.state == "running" and alive(info.pid)
            # ...and new connections are served.
            async with await daemon.connect() as other:
                assert [p.name for p in await other.list()] == ["keep"]
            await client.stop("keep")

    asyncio.run(main())
    log = daemon.log_text()
    assert "exceeds the limit" in log and "malformed frame" in log


def test_malformed_request_after_auth(daemon: Daemon) -> None:
    conn = RawConnection(daemon.port)
    try:
        conn.authenticate(daemon.key, daemon.instance)
        conn.send(conn.frame(dw.Msg.SPAWN, 5, b"\x05\x00\x00"))  # a truncated payload
        code, text = conn.expect_error_and_close()
        assert (code, text) == (dw.ErrorCode.BAD_REQUEST, "malformed SPAWN request")
    finally:
        conn.close()
    conn = RawConnection(daemon.port)
    try:
        conn.authenticate(daemon.key, daemon.instance)
        conn.send(conn.frame(0x7F, 6, b""))
        code, text = conn.expect_error_and_close()
        assert text == "unknown message type 127"
    finally:
        conn.close()

    async def main() -> None:
        async with await daemon.connect() as client:
            await client.ping()

    asyncio.run(main())


def test_oversized_frame_before_authentication_is_refused_at_once(daemon: Daemon) -> None:
    # Before the handshake only a CLIENT_HELLO is acceptable, so a longer frame is refused
    # as soon as its length is read: an unauthenticated peer cannot make the daemon hold
    # megabytes per connection while it waits for a body that never comes.
    for length in (4 << 20, 339):
        conn = RawConnection(daemon.port)
        try:
            conn.hello()
            conn.send(struct.pack("<I", length))
            code, text = conn.expect_error_and_close()
            assert code == dw.ErrorCode.BAD_REQUEST, text
            assert text == f"frame of {length} bytes exceeds the limit of 338 before the handshake"
        finally:
            conn.close()
    # The largest CLIENT_HELLO (an instance name of 255 bytes) still fits.
    conn = RawConnection(daemon.port)
    try:
        conn.authenticate(daemon.key, "i" * 255)
    finally:
        conn.close()


def test_silent_and_half_open_connections(daemon: Daemon) -> None:
    # Connections that say nothing, or half a frame, do not block anybody else.
    idle = [socket.create_connection(("127.0.0.1", daemon.port)) for _ in range(5)]
    half = RawConnection(daemon.port)
    half.hello()
    half.send(struct.pack("<I", 300) + b"only part of it")
    try:
        async def main() -> None:
            async with await daemon.connect() as client:
                await client.spawn(spec("p", "echo ok"))
                await line(client, "p", "ok")

        asyncio.run(main())
    finally:
        for s in idle:
            s.close()
        half.close()


def test_client_refuses_oversized_requests(daemon: Daemon) -> None:
    async def main() -> None:
        async with await daemon.connect() as client:
            huge = spec("huge", "true")
            huge.env = {"BIG": "x" * (5 << 20)}
            try:
                await client.spawn(huge)
            except dw.DaemonError as e:
                assert "exceeds the frame limit" in str(e)
            else:
                raise AssertionError("an oversized request was sent")
            await client.ping()  # nothing was sent, the connection is fine

    asyncio.run(main())


def test_unauthenticated_connections_cannot_lock_out_a_manager(daemon: Daemon) -> None:
    # Peers that never authenticate hold every connection slot (a slow-loris): a manager with
    # the key still gets in, taking the slot of the oldest of them, and so does the next one.
    idle = []
    try:
        for _ in range(256):
            conn = RawConnection(daemon.port)
            nonce = conn.hello()  # accepted: the daemon greeted it
            idle.append(conn)

        async def main() -> None:
            async with await daemon.connect() as first, await daemon.connect() as second:
                await first.ping()
                await second.ping()

        asyncio.run(main())
        # The oldest unauthenticated ones made room; the newest are still served.
        code, text = idle[0].expect_error_and_close()
        assert (code, text) == (dw.ErrorCode.NOT_AUTHENTICATED,
                                "connection slot needed by a newer connection")
        newest = idle[-1]
        newest.send(newest.client_hello(daemon.key, daemon.instance, nonce))
        assert newest.read_frame()[0] == dw.Msg.AUTH_OK
    finally:
        for conn in idle:
            conn.close()
