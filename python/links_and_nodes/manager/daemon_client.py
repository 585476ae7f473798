"""Asyncio client of ln_daemon, the per-host process supervisor (protocol in docs/daemon.md).

The manager's scheduler starts, stops and watches processes through `DaemonClient`; key
files and starting a local daemon are here too.  Authentication and frame tags use only
hmac/hashlib/secrets from the standard library.
"""

from __future__ import annotations

import asyncio
import contextlib
import enum
import hashlib
import hmac
import os
import secrets
import shlex
import shutil
import stat
import struct
from dataclasses import dataclass, field
from pathlib import Path

from . import daemon_pull
from .daemon_payload import Malformed as _Malformed
from .daemon_payload import PayloadReader as _Reader
from .daemon_payload import encode_str as _str

PROTOCOL_VERSION = 1
MAGIC = b"LNDAEMON"
MAX_FRAME = 4 << 20  # bytes after the length field, both directions
NONCE_BYTES = 32
TAG_BYTES = 32
KEY_BYTES = 32


class Msg(enum.IntEnum):
    DAEMON_HELLO = 0x01
    CLIENT_HELLO = 0x02
    AUTH_OK = 0x03
    SPAWN = 0x10
    STOP = 0x11
    SIGNAL = 0x12
    LIST = 0x13
    OUTPUT = 0x14
    FORGET = 0x15
    PING = 0x16
    NET_INFO = 0x40
    RING_CREATE = 0x41
    RING_RETIRE = 0x42
    RING_READER = 0x43
    RING_COUNTS = 0x44
    RING_REMOVE = 0x45
    RING_PURGE = 0x46
    RING_SEQ = 0x47
    STREAM_SEND = 0x48
    STREAM_RECV = 0x49
    STREAM_REMOVE = 0x4A
    STREAM_STATS = 0x4B
    LOGGER_TOPIC = 0x4C
    LOGGER_REMOVE = 0x4D
    LOGGER_ENABLE = 0x4E
    LOGGER_FETCH = 0x4F
    LOGGER_STATUS = 0x50
    PULL_TOPIC = 0x51
    PULL_REMOVE = 0x52
    PULL_STATUS = 0x53
    OK = 0x20
    ERROR = 0x21
    SPAWNED = 0x22
    PROCESS_LIST = 0x23
    OUTPUT_LINES = 0x24
    NET_DETAILS = 0x25
    VALUE = 0x26
    STREAM_LIST = 0x27
    LOGGER_DATA = 0x28
    LOGGER_LIST = 0x29
    PULL_LIST = 0x2A
    EV_OUTPUT = 0x30
    EV_EXITED = 0x31
    EV_STATE = 0x32


class ErrorCode(enum.IntEnum):
    BAD_REQUEST = 1
    NOT_AUTHENTICATED = 2
    AUTH_FAILED = 3
    VERSION = 4
    UNKNOWN_PROCESS = 5
    ALREADY_RUNNING = 6
    NOT_RUNNING = 7
    STILL_RUNNING = 8
    SPAWN_FAILED = 9
    INVALID_SPEC = 10
    LIMIT = 11
    OS_ERROR = 12
    RING_FAILED = 13
    STREAM_FAILED = 14
    UNKNOWN_STREAM = 15
    LOGGER_FAILED = 16
    PULL_FAILED = 16  # the same number: a pull topic request refused


STREAMS = {0: "pty", 1: "stdout", 2: "stderr"}
STATES = {0: "starting", 1: "running", 2: "stopping", 3: "exited"}
_EXIT_CODE, _EXIT_SIGNAL = 1, 2
_SPAWN_SHELL, _SPAWN_PTY = 1, 2
TRANSPORTS = {"udp": 0, "tcp": 1}
_TRANSPORT_NAMES = {v: k for k, v in TRANSPORTS.items()}
DEFAULT_PORT = 54376  # the LN "arbiter" port


# ---- public data ------------------------------------------------------------------------


@dataclass
class SpawnSpec:
    """What to start.  `command` is a shell command line for /bin/sh -c when `shell` is
    true, else it is split with shlex into argv (argv[0] is looked up in env's PATH).
    `env` is the complete environment.  rlimits: (name, soft, hard), name like "nofile" or
    "RLIMIT_NOFILE", None for unlimited.  policy: SCHED_OTHER/BATCH/IDLE (priority = nice
    value) or SCHED_FIFO/RR (priority 1..99).  output_log: (path, size limit in bytes, 0 for
    none; rotated files kept)."""

    name: str
    command: str
    shell: bool
    env: dict[str, str]
    cwd: str | None = None  # None: "/"
    rlimits: list[tuple[str, int | None, int | None]] = field(default_factory=list)
    policy: str = "SCHED_OTHER"
    priority: int = 0
    affinity: list[int] | None = None
    use_pty: bool = True
    max_output_lines: int = 1000
    output_log: tuple[str, int, int] | None = None
    term_signal: int = 15
    term_timeout: float = 5.0


@dataclass
class ProcessInfo:
    name: str
    pid: int
    state: str  # "running" | "stopping" | "exited"
    exit_code: int | None
    signal: int | None
    started: float  # time.time() of the start
    exited: float | None = None  # time.time() of the exit
    output_lines: int = 0  # lines kept by the daemon (OUTPUT returns at most these)
    output_total: int = 0  # lines seen since the start


@dataclass
class OutputLine:
    name: str
    stream: str  # "stdout" | "stderr" | "pty"
    text: str
    time: float


@dataclass
class Exited:
    name: str
    pid: int
    exit_code: int | None
    signal: int | None
    time: float


@dataclass
class StateChanged:
    """Only with DaemonClient.connect(..., state_events=True): a process changed state."""

    name: str
    pid: int
    state: str


@dataclass(frozen=True)
class NetInfo:
    """What a daemon tells managers about its host: the id its clients report (LN_HOST_ID)
    and the data port other daemons forward topics to."""

    host_id: str
    data_port: int


@dataclass(frozen=True)
class StreamStat:
    """One forwarding stream of this instance on a daemon.  sending: this host sends (else
    it receives); peer: where it sends to, or the last source seen; drops: samples not sent
    (sender) or incomplete samples given up (receiver); stale: received samples not newer
    than the ring's newest; invalid: malformed datagrams or frames of this stream."""

    token: int
    sending: bool
    transport: str  # "udp" | "tcp"
    ring: str
    peer: str
    samples: int
    bytes: int
    drops: int
    stale: int
    invalid: int
    connected: bool
    last_error: str


@dataclass(frozen=True)
class StreamTotals:
    """Receive-side counters of a daemon that belong to no stream (all instances)."""

    unknown_stream: int
    malformed: int


@dataclass(frozen=True)
class LoggerChunk:
    """A LOGGER_FETCH reply: the topic's layout, whether its logger is enabled, its counters
    (received: samples the tap delivered while enabled; stored: in the buffer now; missed:
    sequence numbers it never got while enabled; skipped: not kept because of the divisor;
    dropped: evicted by depth or span), the sequence numbers of the buffer's oldest and
    newest sample (0 when empty) and stored samples as (seq, timestamp_ns, data), oldest
    first."""

    message_size: int
    layout_hash: int
    md_name: str
    enabled: bool
    received: int
    stored: int
    missed: int
    skipped: int
    dropped: int
    first_seq: int
    last_seq: int
    start_seq: int  # the ring's newest seq when the capture began: later ones are logged or missed
    samples: list[tuple[int, int, bytes]]


@dataclass(frozen=True)
class LoggerTopicStatus:
    """One topic of a logger on a daemon; the counters as in LoggerChunk.  last_error: why
    the logger cannot read its ring right now ("" if it can)."""

    logger: str
    topic: str
    ring: str
    md_name: str
    enabled: bool
    depth: int
    divisor: int
    span: float
    message_size: int
    received: int
    stored: int
    missed: int
    skipped: int
    dropped: int
    last_error: str


@dataclass(frozen=True)
class LoggerStatus:
    """A LOGGER_STATUS reply: the daemon's logger memory limit and what all its loggers use
    (every instance), and the topics asked for."""

    memory_limit: int
    memory_used: int
    topics: list[LoggerTopicStatus]


class DaemonError(Exception):
    """A refusal or failure; the text is the daemon's.  `code` is an ErrorCode or None for
    errors found on this side."""

    def __init__(self, message: str, code: ErrorCode | int | None = None) -> None:
        super().__init__(message)
        self.code = code


class DaemonAuthError(DaemonError):
    """Wrong key: the daemon refused us, or it could not prove it holds the key."""


class DaemonConnectionError(DaemonError, ConnectionError):
    """The connection is gone; raised by calls pending then and made afterwards."""


class KeyFileError(DaemonError):
    """A key file that is missing, not private or not a key."""


# ---- key files ----------------------------------------------------------------------------


def default_port() -> int:
    """$LN_ARBITER_PORT, else 54376: where ln_daemon listens unless told otherwise."""
    env = os.environ.get("LN_ARBITER_PORT")
    if not env:
        return DEFAULT_PORT
    try:
        port = int(env)
    except ValueError:
        port = -1
    if not 0 < port < 65536:
        raise DaemonError(f"LN_ARBITER_PORT is not a port number: {env}")
    return port


def default_key_file() -> Path:
    """$LN_DAEMON_KEY_FILE, else ~/.config/links_and_nodes/daemon.key."""
    env = os.environ.get("LN_DAEMON_KEY_FILE")
    if env:
        return Path(env)
    return Path.home() / ".config" / "links_and_nodes" / "daemon.key"


def read_key_file(path: str | os.PathLike[str]) -> bytes:
    """The 32-byte key of a key file, with the daemon's checks: a regular file of ours,
    nothing for group or others, 64 hex digits and an optional newline."""
    path = os.fspath(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC | os.O_NOCTTY)
    except OSError as e:
        raise KeyFileError(f"cannot open key file '{path}': {e.strerror}") from e
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise KeyFileError(f"key file '{path}' is not a regular file")
        if st.st_uid != os.geteuid():
            raise KeyFileError(f"key file '{path}' is owned by uid {st.st_uid}, not by "
                               f"uid {os.geteuid()}")
        if st.st_mode & 0o077:
            raise KeyFileError(f"key file '{path}' is accessible by group or others (mode "
                               f"{stat.S_IMODE(st.st_mode):04o}); it must be private: "
                               f"chmod 600 '{path}'")
        data = os.read(fd, 130)
    finally:
        os.close(fd)
    text = data[:-1] if data.endswith(b"\n") else data
    try:
        if len(text) != 2 * KEY_BYTES:
            raise ValueError
        return bytes.fromhex(text.decode("ascii"))
    except ValueError:
        raise KeyFileError(f"key file '{path}' holds no valid key: it must contain exactly "
                           "64 hex digits (32 bytes), optionally followed by a newline") from None


def create_key_file(path: str | os.PathLike[str]) -> bytes:
    """Write a new random key to `path` (mode 0600; missing parent directories are created
    with mode 0700) and return it.  An existing file is never overwritten."""
    path = Path(path)
    missing = []
    parent = path.parent
    while not parent.exists():
        missing.append(parent)
        parent = parent.parent
    for directory in reversed(missing):
        with contextlib.suppress(FileExistsError):
            directory.mkdir(mode=0o700)
    key = secrets.token_bytes(KEY_BYTES)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o600)
    try:
        os.fchmod(fd, 0o600)
        os.write(fd, key.hex().encode() + b"\n")
    finally:
        os.close(fd)
    return key


# ---- starting a daemon ----------------------------------------------------------------------


def daemon_executable() -> str:
    """$LN_DAEMON, else the release build of this checkout, else `ln_daemon` from PATH."""
    env = os.environ.get("LN_DAEMON")
    if env:
        return env
    in_tree = Path(__file__).resolve().parents[3] / "build" / "release" / "ln_daemon" / "ln_daemon"
    if os.access(in_tree, os.X_OK):
        return str(in_tree)
    return shutil.which("ln_daemon") or "ln_daemon"


async def _probe(host: str, port: int, timeout: float) -> bool:
    """True if an ln_daemon answers on host:port, False if nothing listens; DaemonError if
    something else does."""
    try:
        reader, writer = await asyncio.wait_for(asyncio.open_connection(host, port), timeout)
    except (TimeoutError, OSError):
        return False
    try:
        head = await asyncio.wait_for(reader.readexactly(4 + 5 + len(MAGIC)), timeout)
    except (TimeoutError, OSError, asyncio.IncompleteReadError):
        head = b""
    finally:
        writer.close()
        with contextlib.suppress(OSError):
            await writer.wait_closed()
    if head[4:5] != bytes([Msg.DAEMON_HELLO]) or head[9:] != MAGIC:
        raise DaemonError(f"{host}:{port} is in use by something that is not ln_daemon")
    return True


async def ensure_local_daemon(port: int, key_file: Path, log_file: Path | None = None,
                              timeout: float = 10.0, *, data_port: int | None = None) -> None:
    """Make sure an ln_daemon listens on 127.0.0.1:`port`: if none answers, start one with
    `key_file` (and `log_file`, and `data_port` for forwarding: None is the daemon's
    default, port + 1; 0 a free one) in its own session, so it outlives the caller, and
    return once it accepts connections.  DaemonError with the daemon's message if it cannot
    start."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    if await _probe("127.0.0.1", port, timeout):
        return
    args = [daemon_executable(), "--port", str(port), "--key-file", os.fspath(key_file)]
    if log_file is not None:
        args += ["--log", os.fspath(log_file)]
    if data_port is not None:
        args += ["--data-port", str(data_port)]
    try:
        # Without --foreground the daemon detaches itself once it listens; this process
        # is only its launcher and ends at once with the start-up verdict.
        proc = await asyncio.create_subprocess_exec(
            *args, stdin=asyncio.subprocess.DEVNULL, stdout=asyncio.subprocess.DEVNULL,
            stderr=asyncio.subprocess.PIPE, start_new_session=True)
    except OSError as e:
        raise DaemonError(f"cannot run {args[0]}: {e.strerror}") from e
    try:
        _, err = await asyncio.wait_for(proc.communicate(), max(0.1, deadline - loop.time()))
    except TimeoutError:
        proc.kill()
        await proc.wait()
        raise DaemonError(f"ln_daemon did not start within {timeout} s") from None
    if proc.returncode != 0:
        # Another caller may have won the race for the port.
        if await _probe("127.0.0.1", port, max(0.1, deadline - loop.time())):
            return
        message = err.decode(errors="replace").strip() or f"exit status {proc.returncode}"
        raise DaemonError(f"ln_daemon did not start: {message}")
    while not await _probe("127.0.0.1", port, max(0.1, deadline - loop.time())):
        if loop.time() > deadline:
            raise DaemonError(f"ln_daemon started but does not accept on port {port}")
        await asyncio.sleep(0.05)


# ---- wire encoding ---------------------------------------------------------------------------


def _proofs(key: bytes, daemon_nonce: bytes, client_nonce: bytes,
            instance: bytes) -> dict[str, bytes]:
    def mac(k: bytes, label: str) -> bytes:
        return hmac.new(k, label.encode() + b"\0" + daemon_nonce + client_nonce + instance,
                        hashlib.sha256).digest()

    return {"client": mac(key, "ln_daemon/1 client proof"),
            "daemon": mac(key, "ln_daemon/1 daemon proof"),
            "to_daemon": mac(key, "ln_daemon/1 to daemon"),
            "to_client": mac(key, "ln_daemon/1 to client")}


def _frame_tag(key: bytes, seq: int, body: bytes) -> bytes:
    return hmac.new(key, struct.pack("<Q", seq) + body, hashlib.sha256).digest()


def _encode_spawn(spec: SpawnSpec) -> bytes:
    if spec.shell:
        argv = [spec.command]
    else:
        try:
            argv = shlex.split(spec.command)
        except ValueError as e:
            raise DaemonError(f"cannot split command of {spec.name}: {e}") from None
    try:
        out = [_str(spec.name),
               struct.pack("<B", (_SPAWN_SHELL if spec.shell else 0)
                           | (_SPAWN_PTY if spec.use_pty else 0)),
               struct.pack("<I", len(argv)), *(_str(a) for a in argv),
               struct.pack("<I", len(spec.env)),
               *(_str(f"{k}={v}") for k, v in spec.env.items()),
               _str(spec.cwd or ""),
               struct.pack("<I", len(spec.rlimits))]
        for name, soft, hard in spec.rlimits:
            out += [_str(name), struct.pack("<qq", -1 if soft is None else soft,
                                            -1 if hard is None else hard)]
        affinity = spec.affinity or []
        log_path, log_limit, log_keep = spec.output_log or ("", 0, 0)
        out += [_str(spec.policy), struct.pack("<i", spec.priority),
                struct.pack(f"<I{len(affinity)}I", len(affinity), *affinity),
                struct.pack("<I", spec.max_output_lines),
                _str(log_path), struct.pack("<QI", log_limit, log_keep),
                struct.pack("<id", spec.term_signal, spec.term_timeout)]
    except struct.error as e:
        raise DaemonError(f"invalid spawn spec for {spec.name}: {e}") from None
    return b"".join(out)


def _decode_info(r: _Reader) -> ProcessInfo:
    name = r.text()
    pid, state, kind, value, started, exited, kept, total = r.take("<IBBiddIQ")
    return ProcessInfo(name=name, pid=pid, state=STATES.get(state, str(state)),
                       exit_code=value if kind == _EXIT_CODE else None,
                       signal=value if kind == _EXIT_SIGNAL else None, started=started,
                       exited=exited if STATES.get(state) == "exited" else None,
                       output_lines=kept, output_total=total)


def _pack(what: str, fmt: str, *values: object) -> bytes:
    try:
        return struct.pack(fmt, *values)
    except struct.error as e:
        raise DaemonError(f"invalid {what}: {e}") from None


def _transport(transport: str) -> int:
    try:
        return TRANSPORTS[transport]
    except KeyError:
        raise DaemonError(f"unknown transport {transport!r} (known: udp, tcp)") from None


def _decode_stream_list(payload: bytes) -> tuple[list[StreamStat], StreamTotals]:
    r = _Reader(payload)
    unknown, malformed, count = r.take("<QQI")
    streams = []
    for _ in range(count):
        token, sending, transport = r.take("<QBB")
        ring, peer = r.text(), r.text()
        samples, nbytes, drops, stale, invalid, connected = r.take("<QQQQQB")
        streams.append(StreamStat(
            token=token, sending=bool(sending),
            transport=_TRANSPORT_NAMES.get(transport, str(transport)),
            ring=ring, peer=peer, samples=samples, bytes=nbytes, drops=drops, stale=stale,
            invalid=invalid, connected=bool(connected), last_error=r.text()))
    return streams, StreamTotals(unknown_stream=unknown, malformed=malformed)


def _decode_logger_chunk(payload: bytes) -> LoggerChunk:
    r = _Reader(payload)
    message_size, layout_hash = r.take("<QQ")
    md_name = r.text()
    enabled, received, stored, missed, skipped, dropped, first, last, start, count = \
        r.take("<BQQQQQQQQI")
    samples = []
    for _ in range(count):
        seq, timestamp_ns = r.take("<Qq")
        if r.pos + message_size > len(r.data):
            raise _Malformed("short payload")
        samples.append((seq, timestamp_ns, r.data[r.pos:r.pos + message_size]))
        r.pos += message_size
    if r.pos != len(r.data):
        raise _Malformed("bytes left over")
    return LoggerChunk(message_size=message_size, layout_hash=layout_hash, md_name=md_name,
                       enabled=bool(enabled), received=received, stored=stored, missed=missed,
                       skipped=skipped, dropped=dropped, first_seq=first, last_seq=last,
                       start_seq=start, samples=samples)


def _decode_logger_list(payload: bytes) -> LoggerStatus:
    r = _Reader(payload)
    limit, used, count = r.take("<QQI")
    topics = []
    for _ in range(count):
        logger, topic, ring, md_name = r.text(), r.text(), r.text(), r.text()
        enabled, depth, divisor, span, message_size, received, stored, missed, skipped, \
            dropped = r.take("<BIIdQQQQQQ")
        topics.append(LoggerTopicStatus(
            logger=logger, topic=topic, ring=ring, md_name=md_name, enabled=bool(enabled),
            depth=depth, divisor=divisor, span=span, message_size=message_size,
            received=received, stored=stored, missed=missed, skipped=skipped, dropped=dropped,
            last_error=r.text()))
    return LoggerStatus(memory_limit=limit, memory_used=used, topics=topics)


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
        self._events: asyncio.Queue[OutputLine | Exited | StateChanged | None] = asyncio.Queue()
        self._state_events = state_events
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
                code, text = _decode_error(body[5:])
                cls_ = DaemonAuthError if code == ErrorCode.AUTH_FAILED else DaemonError
                raise cls_(text, code)
            return body[0], body[5:]

        mtype, payload = await frame()
        if mtype != Msg.DAEMON_HELLO or len(payload) != 8 + 2 + NONCE_BYTES \
                or payload[:8] != MAGIC:
            raise DaemonError("the peer is not an ln_daemon")
        (version,) = struct.unpack_from("<H", payload, 8)
        if version != PROTOCOL_VERSION:
            raise DaemonError(f"the daemon speaks protocol version {version}; this client "
                              f"speaks {PROTOCOL_VERSION}")
        daemon_nonce = payload[10:]
        client_nonce = secrets.token_bytes(NONCE_BYTES)
        name = instance.encode()
        keys = _proofs(key, daemon_nonce, client_nonce, name)
        hello = MAGIC + struct.pack("<H", PROTOCOL_VERSION) + client_nonce + _str(name) \
            + keys["client"]
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
        tag = _frame_tag(self._to_daemon, self._seq_out, body)
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
                if not hmac.compare_digest(tag, _frame_tag(self._to_client, self._seq_in, body)):
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
        except _Malformed as e:
            reason = f"malformed event from the daemon: {e}"
        except asyncio.CancelledError:
            reason = "connection closed"
        finally:
            self._shutdown(reason)

    def _dispatch_event(self, mtype: int, payload: bytes) -> None:
        r = _Reader(payload)
        if mtype == Msg.EV_OUTPUT:
            name = r.text()
            stream, when = r.take("<Bd")
            self._events.put_nowait(OutputLine(name, STREAMS.get(stream, str(stream)),
                                               r.text(), when))
        elif mtype == Msg.EV_EXITED:
            name = r.text()
            pid, kind, value, when = r.take("<IBid")
            self._events.put_nowait(Exited(name, pid, value if kind == _EXIT_CODE else None,
                                           value if kind == _EXIT_SIGNAL else None, when))
        elif mtype == Msg.EV_STATE:
            name = r.text()
            pid, state = r.take("<IB")
            if self._state_events:
                self._events.put_nowait(StateChanged(name, pid, STATES.get(state, str(state))))
        elif mtype == Msg.ERROR:
            code, text = _decode_error(payload)
            raise _Malformed(f"daemon closes the connection: {text}")

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
            code, text = _decode_error(rpayload)
            raise DaemonError(text, code)
        if rtype != expect:
            raise DaemonError(f"unexpected reply 0x{rtype:02x} to {mtype.name}")
        return rpayload

    # -- the API --

    async def spawn(self, spec: SpawnSpec) -> ProcessInfo:
        """Start a process; its info (state "running", pid) once it runs.  DaemonError with
        the precise reason if it cannot start (command not found, cwd, limits, policy)."""
        payload = await self._call(Msg.SPAWN, _encode_spawn(spec), Msg.SPAWNED)
        return _decode_info(_Reader(payload))

    async def stop(self, name: str) -> None:
        """Send the term signal to the process group; SIGKILL to the whole tree follows
        after the term timeout.  Returns once the stop began; the Exited event follows."""
        await self._call(Msg.STOP, _str(name), Msg.OK)

    async def signal(self, name: str, signo: int, *, group: bool = False) -> None:
        """Send `signo` to the process (or to its process group)."""
        await self._call(Msg.SIGNAL, _str(name) + struct.pack("<iB", signo, group), Msg.OK)

    async def list(self) -> list[ProcessInfo]:
        """Every process of this instance, exited ones included, sorted by name."""
        r = _Reader(await self._call(Msg.LIST, b"", Msg.PROCESS_LIST))
        (count,) = r.take("<I")
        return [_decode_info(r) for _ in range(count)]

    async def output(self, name: str, n: int = 100) -> list[OutputLine]:
        """The last `n` output lines the daemon keeps of `name`, oldest first."""
        r = _Reader(await self._call(Msg.OUTPUT, _str(name) + struct.pack("<I", n),
                                     Msg.OUTPUT_LINES))
        (count,) = r.take("<I")
        lines = []
        for _ in range(count):
            stream, when = r.take("<Bd")
            lines.append(OutputLine(name, STREAMS.get(stream, str(stream)), r.text(), when))
        return lines

    async def forget(self, name: str) -> None:
        """Drop the record of an exited process."""
        await self._call(Msg.FORGET, _str(name), Msg.OK)

    async def ping(self) -> None:
        await self._call(Msg.PING, b"", Msg.OK)

    # -- rings and forwarding (docs/daemon.md, "Rings and forwarding") --
    # Ring names must lie in this instance's namespace, /ln.<sanitized instance>.*; a
    # failing libln call raises DaemonError with code RING_FAILED and libln's text.

    async def net_info(self) -> NetInfo:
        """The daemon's host id and the data port it advertises."""
        try:
            r = _Reader(await self._call(Msg.NET_INFO, b"", Msg.NET_DETAILS))
            host_id = r.text()
            (port,) = r.take("<H")
        except _Malformed as e:
            raise DaemonError(f"malformed NET_INFO reply: {e}") from None
        return NetInfo(host_id=host_id, data_port=port)

    async def ring_create(self, name: str, topic: str, md_name: str, layout_hash: int,
                          message_size: int, slots: int, *, adopt: bool = False) -> None:
        """Create a topic's ring segment on the daemon's host.  adopt: take over the
        segment if it exists (e.g. after a daemon restart) instead of failing."""
        await self._call(Msg.RING_CREATE, _str(name) + _str(topic) + _str(md_name)
                         + _pack("ring", "<QQIB", layout_hash, message_size, slots, adopt),
                         Msg.OK)

    async def ring_retire(self, old: str, successor: str, timeout: float = 1.0) -> None:
        """Hand ring `old` over to `successor` (created before); `timeout` bounds the wait
        for a publisher's loan (0..10 s; the daemon waits in its poll loop)."""
        await self._call(Msg.RING_RETIRE, _str(old) + _str(successor)
                         + _pack("timeout", "<d", timeout), Msg.OK)

    async def ring_reserve_reader(self, name: str, index: int, pid: int, buffers: int) -> None:
        await self._call(Msg.RING_READER, _str(name)
                         + _pack("reader slot", "<IiIB", index, pid, buffers, 1), Msg.OK)

    async def ring_release_reader(self, name: str, index: int) -> None:
        await self._call(Msg.RING_READER, _str(name)
                         + _pack("reader slot", "<IiIB", index, 0, 0, 0), Msg.OK)

    async def ring_set_counts(self, name: str, publishers: int, subscribers: int) -> None:
        await self._call(Msg.RING_COUNTS, _str(name)
                         + _pack("port counts", "<II", publishers, subscribers), Msg.OK)

    async def ring_remove(self, name: str) -> None:
        """Close the daemon's handle of the ring (if any) and unlink the segment."""
        await self._call(Msg.RING_REMOVE, _str(name), Msg.OK)

    async def ring_purge(self) -> int:
        """Unlink every segment of this instance on the daemon's host, close its handles and
        remove its streams; how many segments were unlinked."""
        return await self._value(Msg.RING_PURGE, b"")

    async def ring_write_seq(self, name: str) -> int:
        """The newest sequence number written into the ring (0: none yet)."""
        return await self._value(Msg.RING_SEQ, _str(name))

    async def stream_send(self, token: int, ring: str, layout_hash: int, message_size: int,
                          transport: str, host: str, port: int) -> None:
        """Send every sample of local `ring` to the daemon at host:port (its data port),
        which writes them into the ring it has for `token`.  Replaces a stream of the same
        token.  DaemonError STREAM_FAILED with the forwarder's reason."""
        await self._call(Msg.STREAM_SEND, _pack("token", "<Q", token) + _str(ring)
                         + _pack("stream", "<QQB", layout_hash, message_size,
                                 _transport(transport))
                         + _str(host) + _pack("port", "<H", port), Msg.OK)

    async def stream_recv(self, token: int, ring: str, layout_hash: int, message_size: int,
                          transport: str) -> None:
        """Write the samples arriving for `token` into local `ring`."""
        await self._call(Msg.STREAM_RECV, _pack("token", "<Q", token) + _str(ring)
                         + _pack("stream", "<QQB", layout_hash, message_size,
                                 _transport(transport)), Msg.OK)

    async def stream_remove(self, token: int) -> None:
        """Stop a stream of this instance; DaemonError UNKNOWN_STREAM if there is none."""
        await self._call(Msg.STREAM_REMOVE, _pack("token", "<Q", token), Msg.OK)

    async def stream_stats(self) -> tuple[list[StreamStat], StreamTotals]:
        """Counters of this instance's streams, and the daemon's counters of traffic that
        belongs to no stream."""
        payload = await self._call(Msg.STREAM_STATS, b"", Msg.STREAM_LIST)
        try:
            return _decode_stream_list(payload)
        except _Malformed as e:
            raise DaemonError(f"malformed STREAM_STATS reply: {e}") from None

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
        await self._call(Msg.LOGGER_TOPIC, _str(logger) + _str(topic) + _str(ring)
                         + _str(md_name)
                         + _pack("logger topic", "<QQIId", layout_hash, message_size, depth,
                                 divisor, span), Msg.OK)

    async def logger_remove(self, logger: str, topic: str = "") -> None:
        """Remove one topic of `logger`, or with topic "" the whole logger, and its data."""
        await self._call(Msg.LOGGER_REMOVE, _str(logger) + _str(topic), Msg.OK)

    async def logger_enable(self, logger: str, enable: bool = True, clear: bool = False) -> None:
        """Start logging every topic of `logger` (samples published from now on), or stop
        it, keeping the data; `clear` first empties the buffers and zeroes the counters."""
        await self._call(Msg.LOGGER_ENABLE, _str(logger) + struct.pack("<BB", enable, clear),
                         Msg.OK)

    async def logger_fetch(self, logger: str, topic: str, after_seq: int = 0,
                           max_bytes: int = 1 << 20) -> LoggerChunk:
        """The stored samples of a logger topic with seq > after_seq, oldest first, as many
        as fit `max_bytes` (16 + message size each; at least one if there is any)."""
        payload = await self._call(Msg.LOGGER_FETCH, _str(logger) + _str(topic)
                                   + _pack("fetch", "<QI", after_seq, max_bytes),
                                   Msg.LOGGER_DATA)
        try:
            return _decode_logger_chunk(payload)
        except _Malformed as e:
            raise DaemonError(f"malformed LOGGER_FETCH reply: {e}") from None

    async def logger_status(self, logger: str = "") -> LoggerStatus:
        """Every topic of `logger` ("": of every logger of this instance) and the daemon's
        logger memory."""
        payload = await self._call(Msg.LOGGER_STATUS, _str(logger), Msg.LOGGER_LIST)
        try:
            return _decode_logger_list(payload)
        except _Malformed as e:
            raise DaemonError(f"malformed LOGGER_STATUS reply: {e}") from None

    # -- pull topics (docs/pull.md); refusals raise DaemonError PULL_FAILED with the text --
    async def pull_topic(self, topic: str, ring: str, md_name: str, layout_hash: int,
                         message_size: int, address: str, port: int, name: str,
                         history: int, freshness_ms: int, key: bytes = b"") -> None:
        """Serve local `ring` as the NDN name `name` on UDP `address`:`port`."""
        try:
            payload = daemon_pull.encode_pull_topic(topic, ring, md_name, layout_hash,
                                                    message_size, address, port, name,
                                                    history, freshness_ms, key)
        except struct.error as e:
            raise DaemonError(f"invalid pull topic {topic!r}: {e}") from None
        await self._call(Msg.PULL_TOPIC, payload, Msg.OK)

    async def pull_remove(self, topic: str = "") -> None:
        """Stop serving `topic` ("": every pull topic of this instance)."""
        await self._call(Msg.PULL_REMOVE, _str(topic), Msg.OK)

    async def pull_status(self, topic: str = "") -> daemon_pull.PullStatus:
        """The producer's ports and `topic` ("": every pull topic of this instance)."""
        payload = await self._call(Msg.PULL_STATUS, _str(topic), Msg.PULL_LIST)
        try:
            return daemon_pull.decode_pull_list(payload)
        except ValueError as e:
            raise DaemonError(f"malformed PULL_STATUS reply: {e}") from None

    async def _value(self, mtype: Msg, payload: bytes) -> int:
        reply = await self._call(mtype, payload, Msg.VALUE)
        if len(reply) != 8:
            raise DaemonError(f"malformed {mtype.name} reply of {len(reply)} bytes")
        return int(struct.unpack("<Q", reply)[0])

    def events(self) -> asyncio.Queue[OutputLine | Exited | StateChanged | None]:
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


def _decode_error(payload: bytes) -> tuple[ErrorCode | int, str]:
    try:
        r = _Reader(payload)
        (code,) = r.take("<H")
        text = r.text()
    except _Malformed:
        return ErrorCode.BAD_REQUEST, "malformed error from the daemon"
    with contextlib.suppress(ValueError):
        code = ErrorCode(code)
    return code, text
