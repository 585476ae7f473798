"""Asyncio client of ln_daemon, the per-host process supervisor (protocol in docs/daemon.md,
its codec in daemon_wire.py): one authenticated connection whose calls start, stop and watch
processes, rings, streams, loggers and pull topics.  The scheduler drives it."""

from __future__ import annotations

import asyncio
import contextlib
import hmac
import secrets
import struct
from collections.abc import Callable
from typing import Any, TypeVar

from ...wire.codec import WireError
from ..network import daemon_pull
from .daemon_resources import ResourceSample, decode_resources
from .daemon_wire import (
    DEFAULT_SECURITY,
    EXIT_CODE,
    EXIT_SIGNAL,
    KEY_BYTES,
    MAGIC,
    MAX_FRAME,
    NONCE_BYTES,
    PROTOCOL_VERSION,
    STATES,
    STREAMS,
    TAG_BYTES,
    DaemonAuthError,
    DaemonConnectionError,
    DaemonError,
    ErrorCode,
    Exited,
    LoggerChunk,
    LoggerStatus,
    Msg,
    NetInfo,
    OutputLine,
    ProcessInfo,
    SpawnSpec,
    StateChanged,
    StreamStat,
    StreamTotals,
    decode,
    decode_error,
    decode_logger_chunk,
    decode_logger_list,
    decode_stream_list,
    encode,
    encode_spawn,
    frame_tag,
    process_info,
    proofs,
    security_code,
    transport_code,
)

_T = TypeVar("_T")

# ---- the client ------------------------------------------------------------------------------


class DaemonClient:
    """One authenticated connection to an ln_daemon, for one instance.

    Calls may run concurrently.  Events (output lines, exits) of the instance's processes
    arrive in the queue returned by events(); when the connection ends for whatever reason,
    the queue gets None as its last item, pending calls raise DaemonConnectionError (a
    DaemonError and a ConnectionError), and so do later calls.
    """

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter,
                 instance: str, keys: dict[str, bytes], state_events: bool) -> None:
        self._reader = reader
        self._writer = writer
        self.instance = instance
        self._to_daemon = keys["to_daemon"]
        self._to_client = keys["to_client"]
        self._seq_out = 0
        self._seq_in = 0
        self._next_req = 1
        self._pending: dict[int, asyncio.Future[tuple[int, bytes]]] = {}
        self._events: asyncio.Queue[OutputLine | Exited | StateChanged | ResourceSample | None] \
            = asyncio.Queue()
        self._state_events = state_events
        self._resource_events = False  # after resources(): ResourceSample events
        self._closed: str | None = None
        self._task = asyncio.get_running_loop().create_task(self._read_loop())

    @classmethod
    async def connect(cls, host: str, port: int, key: bytes, instance: str, *,
                      timeout: float = 10.0, state_events: bool = False) -> DaemonClient:
        """Connect and authenticate (both ways).  DaemonAuthError for a wrong key,
        DaemonError for other refusals, OSError/TimeoutError if the daemon is unreachable."""
        if len(key) != KEY_BYTES:
            raise DaemonError(f"the key must be {KEY_BYTES} bytes, got {len(key)}")
        reader, writer = await asyncio.wait_for(asyncio.open_connection(host, port), timeout)
        try:
            keys = await asyncio.wait_for(cls._handshake(reader, writer, key, instance), timeout)
        except BaseException:
            writer.close()
            raise
        return cls(reader, writer, instance, keys, state_events)

    @staticmethod
    async def _handshake(reader: asyncio.StreamReader, writer: asyncio.StreamWriter,
                         key: bytes, instance: str) -> dict[str, bytes]:
        async def frame() -> tuple[int, bytes]:
            try:
                (length,) = struct.unpack("<I", await reader.readexactly(4))
                if not 5 <= length <= MAX_FRAME:
                    raise DaemonError(f"bad frame length {length} in the handshake")
                body = await reader.readexactly(length)
            except (asyncio.IncompleteReadError, ConnectionError) as e:
                raise DaemonConnectionError(
                    "the daemon closed the connection during the handshake") from e
            if body[0] == Msg.ERROR:
                code, text = decode_error(body[5:])
                cls_ = DaemonAuthError if code == ErrorCode.AUTH_FAILED else DaemonError
                raise cls_(text, code)
            return body[0], body[5:]

        mtype, payload = await frame()
        try:
            daemon_hello = decode("DAEMON_HELLO", payload)
        except WireError:
            daemon_hello = {}
        if mtype != Msg.DAEMON_HELLO or daemon_hello.get("magic") != MAGIC:
            raise DaemonError("the peer is not an ln_daemon")
        version = daemon_hello["version"]
        if version != PROTOCOL_VERSION:
            raise DaemonError(f"the daemon speaks protocol version {version}; this client "
                              f"speaks {PROTOCOL_VERSION}")
        daemon_nonce = daemon_hello["nonce"]
        client_nonce = secrets.token_bytes(NONCE_BYTES)
        name = instance.encode()
        keys = proofs(key, daemon_nonce, client_nonce, name)
        hello = encode("CLIENT_HELLO", {"magic": MAGIC, "version": PROTOCOL_VERSION,
                                        "nonce": client_nonce, "instance": name,
                                        "proof": keys["client"]})
        writer.write(struct.pack("<IBI", 5 + len(hello), Msg.CLIENT_HELLO, 0) + hello)
        await writer.drain()
        mtype, payload = await frame()
        if mtype != Msg.AUTH_OK or len(payload) != TAG_BYTES:
            raise DaemonError(f"unexpected handshake reply 0x{mtype:02x}")
        if not hmac.compare_digest(payload, keys["daemon"]):
            raise DaemonAuthError("the daemon could not prove that it holds the key")
        return keys

    # -- plumbing --

    def _send(self, mtype: int, req: int, payload: bytes) -> None:
        body = struct.pack("<BI", mtype, req) + payload
        if len(body) + TAG_BYTES > MAX_FRAME:
            raise DaemonError(f"request of {len(body)} bytes exceeds the frame limit")
        tag = frame_tag(self._to_daemon, self._seq_out, body)
        self._seq_out += 1
        self._writer.write(struct.pack("<I", len(body) + TAG_BYTES) + body + tag)

    async def _read_loop(self) -> None:
        reason = "connection closed by the daemon"
        try:
            while True:
                (length,) = struct.unpack("<I", await self._reader.readexactly(4))
                if not 5 + TAG_BYTES <= length <= MAX_FRAME:
                    reason = f"bad frame length {length} from the daemon"
                    break
                frame = await self._reader.readexactly(length)
                body, tag = frame[:-TAG_BYTES], frame[-TAG_BYTES:]
                if not hmac.compare_digest(tag, frame_tag(self._to_client, self._seq_in, body)):
                    reason = "frame with a wrong tag from the daemon"
                    break
                self._seq_in += 1
                mtype, req = struct.unpack_from("<BI", body)
                payload = body[5:]
                if req:
                    future = self._pending.pop(req, None)
                    if future is not None and not future.done():
                        future.set_result((mtype, payload))
                else:
                    self._dispatch_event(mtype, payload)
        except (asyncio.IncompleteReadError, ConnectionError, OSError) as e:
            reason = f"connection to the daemon lost: {e}" \
                if not isinstance(e, asyncio.IncompleteReadError) else reason
        except WireError as e:
            reason = f"malformed event from the daemon: {e}"
        except asyncio.CancelledError:
            reason = "connection closed"
        finally:
            self._shutdown(reason)

    def _dispatch_event(self, mtype: int, payload: bytes) -> None:
        if mtype == Msg.EV_OUTPUT:
            f = decode("EV_OUTPUT", payload)
            self._events.put_nowait(OutputLine(f["name"], STREAMS[f["stream"]], f["text"],
                                               f["time"]))
        elif mtype == Msg.EV_EXITED:
            f = decode("EV_EXITED", payload)
            kind, value = f["exit_kind"], f["exit_value"]
            self._events.put_nowait(Exited(f["name"], f["pid"],
                                           value if kind == EXIT_CODE else None,
                                           value if kind == EXIT_SIGNAL else None, f["time"]))
        elif mtype == Msg.EV_STATE:
            f = decode("EV_STATE", payload)
            if self._state_events:
                self._events.put_nowait(StateChanged(f["name"], f["pid"], STATES[f["state"]]))
        elif mtype == Msg.EV_RESOURCES:
            if self._resource_events:
                self._events.put_nowait(decode_resources(payload))
        elif mtype == Msg.ERROR:
            code, text = decode_error(payload)
            raise WireError(f"daemon closes the connection: {text}")

    def _shutdown(self, reason: str) -> None:
        if self._closed is not None:
            return
        self._closed = reason
        for future in self._pending.values():
            if not future.done():
                future.set_exception(DaemonConnectionError(reason))
        self._pending.clear()
        self._events.put_nowait(None)
        self._writer.close()

    async def _call(self, mtype: Msg, payload: bytes, expect: Msg) -> bytes:
        if self._closed is not None:
            raise DaemonConnectionError(self._closed)
        req = self._next_req
        self._next_req = self._next_req % 0xFFFFFFFF + 1
        self._send(mtype, req, payload)  # raises before anything is sent if too large
        future: asyncio.Future[tuple[int, bytes]] = asyncio.get_running_loop().create_future()
        self._pending[req] = future
        with contextlib.suppress(ConnectionError):
            await self._writer.drain()  # a lost connection shows in the reader
        rtype, rpayload = await future
        if rtype == Msg.ERROR:
            code, text = decode_error(rpayload)
            raise DaemonError(text, code)
        if rtype != expect:
            raise DaemonError(f"unexpected reply 0x{rtype:02x} to {mtype.name}")
        return rpayload

    async def _request(self, mtype: Msg, fields: dict[str, Any], expect: Msg,
                       convert: Callable[[bytes], _T]) -> _T:
        """Send request `mtype` with `fields` (named as in wire/daemon.schema) and convert
        its `expect` reply; DaemonError for a value that does not fit or a malformed reply."""
        payload = await self._call(mtype, encode(mtype.name, fields), expect)
        try:
            return convert(payload)
        except WireError as e:
            raise DaemonError(f"malformed {mtype.name} reply: {e}") from None

    async def _ok(self, mtype: Msg, **fields: Any) -> None:
        await self._request(mtype, fields, Msg.OK, lambda payload: decode("OK", payload))

    # -- the API --

    async def spawn(self, spec: SpawnSpec) -> ProcessInfo:
        """Start a process; its info (state "running", pid) once it runs.  DaemonError with
        the precise reason if it cannot start (command not found, cwd, limits, policy)."""
        payload = await self._call(Msg.SPAWN, encode_spawn(spec), Msg.SPAWNED)
        try:
            return process_info(decode("SPAWNED", payload)["info"])
        except WireError as e:
            raise DaemonError(f"malformed SPAWN reply: {e}") from None

    async def stop(self, name: str) -> None:
        """Send the term signal to the process group; SIGKILL to the whole tree follows
        after the term timeout.  Returns once the stop began; the Exited event follows."""
        await self._ok(Msg.STOP, name=name)

    async def signal(self, name: str, signo: int, *, group: bool = False) -> None:
        """Send `signo` to the process (or to its process group)."""
        await self._ok(Msg.SIGNAL, name=name, signal=signo, group=group)

    async def list(self) -> list[ProcessInfo]:
        """Every process of this instance, exited ones included, sorted by name."""
        return await self._request(
            Msg.LIST, {}, Msg.PROCESS_LIST,
            lambda p: [process_info(f) for f in decode("PROCESS_LIST", p)["processes"]])

    async def output(self, name: str, n: int = 100) -> list[OutputLine]:
        """The last `n` output lines the daemon keeps of `name`, oldest first."""
        return await self._request(
            Msg.OUTPUT, {"name": name, "lines": n}, Msg.OUTPUT_LINES,
            lambda p: [OutputLine(name, STREAMS[f["stream"]], f["text"], f["time"])
                       for f in decode("OUTPUT_LINES", p)["lines"]])

    async def forget(self, name: str) -> None:
        """Drop the record of an exited process."""
        await self._ok(Msg.FORGET, name=name)

    async def ping(self) -> None:
        await self._ok(Msg.PING)

    async def resources(self, period: float = 0.0) -> None:
        """Resource samples (ResourceSample events) every `period` seconds (0: the daemon's
        --resource-period; the daemon keeps it within 0.1..3600); a negative period stops
        them.  DaemonError (LIMIT) when the daemon samples nothing (--resource-period 0)."""
        self._resource_events = period >= 0
        await self._ok(Msg.RESOURCES, period=period)

    # -- rings and forwarding (docs/daemon.md, "Rings and forwarding") --
    # Ring names must lie in this instance's namespace, /ln.<sanitized instance>.*; a
    # failing libln call raises DaemonError with code RING_FAILED and libln's text.

    async def net_info(self) -> NetInfo:
        """The daemon's host id and the data port it advertises."""
        f = await self._request(Msg.NET_INFO, {}, Msg.NET_DETAILS,
                                lambda p: decode("NET_DETAILS", p))
        return NetInfo(host_id=f["host_id"], data_port=f["data_port"])

    async def ring_create(self, name: str, topic: str, md_name: str, layout_hash: int,
                          message_size: int, slots: int, *, adopt: bool = False) -> None:
        """Create a topic's ring segment on the daemon's host.  adopt: take over the
        segment if it exists (e.g. after a daemon restart) instead of failing."""
        await self._ok(Msg.RING_CREATE, name=name, topic=topic, md_name=md_name,
                       layout_hash=layout_hash, message_size=message_size, slots=slots,
                       adopt=adopt)

    async def ring_retire(self, old: str, successor: str, timeout: float = 1.0) -> None:
        """Hand ring `old` over to `successor` (created before); `timeout` bounds the wait
        for a publisher's loan (0..10 s; the daemon waits in its poll loop)."""
        await self._ok(Msg.RING_RETIRE, old_name=old, successor=successor, timeout=timeout)

    async def ring_reserve_reader(self, name: str, index: int, pid: int, buffers: int) -> None:
        await self._ok(Msg.RING_READER, name=name, index=index, pid=pid, buffers=buffers,
                       reserve=True)

    async def ring_release_reader(self, name: str, index: int) -> None:
        await self._ok(Msg.RING_READER, name=name, index=index, reserve=False)

    async def ring_set_counts(self, name: str, publishers: int, subscribers: int) -> None:
        await self._ok(Msg.RING_COUNTS, name=name, publishers=publishers,
                       subscribers=subscribers)

    async def ring_remove(self, name: str) -> None:
        """Close the daemon's handle of the ring (if any) and unlink the segment."""
        await self._ok(Msg.RING_REMOVE, name=name)

    async def ring_purge(self) -> int:
        """Unlink every segment of this instance on the daemon's host, close its handles and
        remove its streams; how many segments were unlinked."""
        return await self._value(Msg.RING_PURGE, {})

    async def ring_write_seq(self, name: str) -> int:
        """The newest sequence number written into the ring (0: none yet)."""
        return await self._value(Msg.RING_SEQ, {"name": name})

    async def stream_send(self, token: int, ring: str, layout_hash: int, message_size: int,
                          transport: str, host: str, port: int,
                          security: str = DEFAULT_SECURITY) -> None:
        """Send every sample of local `ring` to the daemon at host:port (its data port),
        which writes them into the ring it has for `token`.  Replaces a stream of the same
        token.  `security` (none, authenticate, encrypt) must be the receiver's as well.
        DaemonError STREAM_FAILED with the forwarder's reason."""
        await self._ok(Msg.STREAM_SEND, token=token, ring=ring, layout_hash=layout_hash,
                       message_size=message_size, transport=transport_code(transport),
                       host=host, port=port, security=security_code(security))

    async def stream_recv(self, token: int, ring: str, layout_hash: int, message_size: int,
                          transport: str, security: str = DEFAULT_SECURITY) -> None:
        """Write the samples arriving for `token` into local `ring`; datagrams and frames
        not protected as `security` says are rejected."""
        await self._ok(Msg.STREAM_RECV, token=token, ring=ring, layout_hash=layout_hash,
                       message_size=message_size, transport=transport_code(transport),
                       security=security_code(security))

    async def stream_remove(self, token: int) -> None:
        """Stop a stream of this instance; DaemonError UNKNOWN_STREAM if there is none."""
        await self._ok(Msg.STREAM_REMOVE, token=token)

    async def stream_stats(self) -> tuple[list[StreamStat], StreamTotals]:
        """Counters of this instance's streams, and the daemon's counters of traffic that
        belongs to no stream."""
        return await self._request(Msg.STREAM_STATS, {}, Msg.STREAM_LIST, decode_stream_list)

    # -- topic logging (docs/daemon.md, "Topic logging") --
    # Loggers belong to this instance and outlive the connection; refusals raise
    # DaemonError with code LOGGER_FAILED (or LIMIT) and the daemon's text.

    async def logger_topic(self, logger: str, topic: str, ring: str, md_name: str,
                           layout_hash: int, message_size: int, depth: int, divisor: int = 1,
                           span: float = 0.0) -> None:
        """Create or update topic `topic` of `logger`: log local `ring` (which may not exist
        yet) into a buffer of `depth` samples, keeping those whose seq is a multiple of
        `divisor`, and with span > 0 none older than the newest's timestamp minus `span`
        seconds.  A new ring of the same shape keeps the data; another message size, depth
        or layout starts a new buffer."""
        await self._ok(Msg.LOGGER_TOPIC, logger=logger, topic=topic, ring=ring,
                       md_name=md_name, layout_hash=layout_hash, message_size=message_size,
                       depth=depth, divisor=divisor, span_s=span)

    async def logger_remove(self, logger: str, topic: str = "") -> None:
        """Remove one topic of `logger`, or with topic "" the whole logger, and its data."""
        await self._ok(Msg.LOGGER_REMOVE, logger=logger, topic=topic)

    async def logger_enable(self, logger: str, enable: bool = True, clear: bool = False) -> None:
        """Start logging every topic of `logger` (samples published from now on), or stop
        it, keeping the data; `clear` first empties the buffers and zeroes the counters."""
        await self._ok(Msg.LOGGER_ENABLE, logger=logger, enable=enable, clear=clear)

    async def logger_fetch(self, logger: str, topic: str, after_seq: int = 0,
                           max_bytes: int = 1 << 20) -> LoggerChunk:
        """The stored samples of a logger topic with seq > after_seq, oldest first, as many
        as fit `max_bytes` (16 + message size each; at least one if there is any)."""
        return await self._request(Msg.LOGGER_FETCH, {"logger": logger, "topic": topic,
                                                      "after_seq": after_seq,
                                                      "max_bytes": max_bytes},
                                   Msg.LOGGER_DATA, decode_logger_chunk)

    async def logger_status(self, logger: str = "") -> LoggerStatus:
        """Every topic of `logger` ("": of every logger of this instance) and the daemon's
        logger memory."""
        return await self._request(Msg.LOGGER_STATUS, {"logger": logger}, Msg.LOGGER_LIST,
                                   decode_logger_list)

    # -- pull topics (docs/pull.md); refusals raise DaemonError PULL_FAILED with the text --
    async def pull_topic(self, topic: str, ring: str, md_name: str, layout_hash: int,
                         message_size: int, address: str, port: int, name: str,
                         history: int, freshness_ms: int, key: bytes = b"") -> None:
        """Serve local `ring` as the NDN name `name` on UDP `address`:`port`."""
        try:
            payload = daemon_pull.encode_pull_topic(topic, ring, md_name, layout_hash,
                                                    message_size, address, port, name,
                                                    history, freshness_ms, key)
        except WireError as e:
            raise DaemonError(f"invalid pull topic {topic!r}: {e}") from None
        await self._call(Msg.PULL_TOPIC, payload, Msg.OK)

    async def pull_remove(self, topic: str = "") -> None:
        """Stop serving `topic` ("": every pull topic of this instance)."""
        await self._ok(Msg.PULL_REMOVE, topic=topic)

    async def pull_status(self, topic: str = "") -> daemon_pull.PullStatus:
        """The producer's ports and `topic` ("": every pull topic of this instance)."""
        return await self._request(Msg.PULL_STATUS, {"topic": topic}, Msg.PULL_LIST,
                                   daemon_pull.decode_pull_list)

    async def _value(self, mtype: Msg, fields: dict[str, Any]) -> int:
        return await self._request(mtype, fields, Msg.VALUE,
                                   lambda p: int(decode("VALUE", p)["value"]))

    def events(self) -> asyncio.Queue[OutputLine | Exited | StateChanged | ResourceSample | None]:
        """The queue of events; None, as the last item, means the connection is gone."""
        return self._events

    @property
    def closed(self) -> bool:
        return self._closed is not None

    @property
    def local_address(self) -> str:
        """This end's address of the connection: one at which the daemon's host reaches
        this host ("" if unknown)."""
        sockname = self._writer.get_extra_info("sockname")
        return str(sockname[0]) if sockname else ""

    async def close(self) -> None:
        """Close the connection; the daemon's processes keep running."""
        if self._closed is None:
            self._task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await self._task
        # a reader cancelled before it ever ran did not get to shut the connection down
        self._shutdown("connection closed")
        with contextlib.suppress(OSError):
            await self._writer.wait_closed()

    async def __aenter__(self) -> DaemonClient:
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()
