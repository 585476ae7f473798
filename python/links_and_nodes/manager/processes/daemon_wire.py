"""The manager's side of the ln_daemon wire protocol (docs/daemon.md): message and error
numbers, the records calls return (SpawnSpec, ProcessInfo, ...), the errors, and their
conversion from and to message payloads, whose layout the schema-driven codec knows
(wire/daemon.schema, wire/codec.py).  Authentication proofs and frame tags use only
hmac/hashlib from the standard library.  No I/O here: daemon_client.py does the talking."""

from __future__ import annotations

import enum
import hashlib
import hmac
import struct
from collections.abc import Mapping
from dataclasses import dataclass, field, make_dataclass
from typing import Any

from ... import transports
from ...wire.codec import DAEMON as _WIRE
from ...wire.codec import WireError
from ..config.argv import CommandSplitError, split_command

# The constants and numbers of the protocol come from wire/daemon.schema.
PROTOCOL_VERSION = int(_WIRE.consts["VERSION"])
MAGIC = str(_WIRE.consts["MAGIC"]).encode()
MAX_FRAME = int(_WIRE.consts["MAX_FRAME"])  # bytes after the length field, both directions
NONCE_BYTES = int(_WIRE.consts["NONCE_BYTES"])
TAG_BYTES = int(_WIRE.consts["TAG_BYTES"])
KEY_BYTES = int(_WIRE.consts["KEY_BYTES"])

Msg = _WIRE.msg
ErrorCode = enum.IntEnum(  # type: ignore[misc]
    "ErrorCode", [(e.name, e.value) for e in _WIRE.schema.enums["Err"].entries])

STREAMS = {0: "pty", 1: "stdout", 2: "stderr"}
STATES = {0: "starting", 1: "running", 2: "stopping", 3: "exited"}
EXIT_CODE = _WIRE.enums["ExitKind"].CODE
EXIT_SIGNAL = _WIRE.enums["ExitKind"].SIGNAL
TRANSPORTS = {name: int(_WIRE.enums["Transport"][name.upper()])
              for name in (transports.UDP, transports.TCP)}
# A stream's protection on the wire between daemons (docs/security.md); the instance's
# `security` key names one, authenticate by default.
SECURITY_LEVELS = {name: int(_WIRE.enums["Security"][name.upper()])
                   for name in ("none", "authenticate", "encrypt")}
DEFAULT_SECURITY = "authenticate"


# ---- public data ------------------------------------------------------------------------


_SPAWN_BITS = {b.name: b.name in (f.default or [])
               for f in _WIRE.schema.messages["SPAWN"].fields if f.type.kind == "flags"
               for b in _WIRE.schema.enums[f.type.ref or ""].entries}


@dataclass
class _SpawnShape:
    """The SPAWN fields the manager holds in another shape than the wire's."""

    name: str
    command: str
    shell: bool
    env: dict[str, str]
    cwd: str | None = None  # None: "/"
    rlimits: list[tuple[str, int | None, int | None]] = field(default_factory=list)
    affinity: list[int] | None = None
    use_pty: bool = _SPAWN_BITS["use_pty"]
    output_log: tuple[str, int, int] | None = None
    argv: list[str] | None = None  # the command's words, split by the configuration


# SPAWN fields that _SpawnShape holds, or converts for encode_spawn.
_SHAPED = {"name", "shell", "use_pty", "argv", "env", "cwd", "rlimits", "affinity", "log_path",
           "log_limit", "log_keep"}
_PY_TYPES = {"int": int, "f64": float, "bool": bool, "str": str, "bytes": bytes}

# What to start.  `command` is a shell command line for /bin/sh -c when `shell` is true, else
# its words are the argv (argv[0] is looked up in env's PATH): `argv` as the configuration
# split it, or, where not given, split by config.argv's rule.  `env` is the complete
# environment.  rlimits: (name, soft, hard), name like "nofile" or "RLIMIT_NOFILE", None for
# unlimited.  output_log: (path, size limit in bytes, 0 for none; rotated files kept).  Every
# other field is the SPAWN field of wire/daemon.schema of that name, with its default there
# (policy: SCHED_OTHER/BATCH/IDLE with priority the nice value, or SCHED_FIFO/RR with
# priority 1..99; max_output_lines; term_signal; term_timeout): a field added to the schema
# is a SpawnSpec attribute at once, and encode_spawn sends it.
def _spawn_field(f: Any) -> Any:
    value = _WIRE.default(f)
    if isinstance(value, (list, dict)):
        return field(default_factory=lambda: type(value)(value))
    return field(default=value)


SpawnSpec = make_dataclass("SpawnSpec", [
    (f.name, _PY_TYPES.get(f.type.kind, object), _spawn_field(f))
    for f in _WIRE.schema.messages["SPAWN"].fields
    if f.type.kind != "flags" and f.name not in _SHAPED], bases=(_SpawnShape,))
SpawnSpec.__module__ = __name__


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
    than the ring's newest; invalid: malformed datagrams or frames of this stream; rejected:
    datagrams, frames or connections that failed authentication (forged, replayed, too old,
    another key or security level)."""

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
    rejected: int
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




# ---- wire encoding ---------------------------------------------------------------------------


def proofs(key: bytes, daemon_nonce: bytes, client_nonce: bytes,
            instance: bytes) -> dict[str, bytes]:
    def mac(k: bytes, label: str) -> bytes:
        return hmac.new(k, label.encode() + b"\0" + daemon_nonce + client_nonce + instance,
                        hashlib.sha256).digest()

    return {"client": mac(key, "ln_daemon/1 client proof"),
            "daemon": mac(key, "ln_daemon/1 daemon proof"),
            "to_daemon": mac(key, "ln_daemon/1 to daemon"),
            "to_client": mac(key, "ln_daemon/1 to client")}


def frame_tag(key: bytes, seq: int, body: bytes) -> bytes:
    return hmac.new(key, struct.pack("<Q", seq) + body, hashlib.sha256).digest()


def encode(message: str, fields: Mapping[str, Any]) -> bytes:
    """The payload of `message` (a Msg name) with `fields` (wire/daemon.schema names them);
    DaemonError for a value that does not fit its field."""
    try:
        return _WIRE.encode(message, fields)
    except WireError as e:
        raise DaemonError(f"invalid {message} request: {e}") from None


def decode(message: str, payload: bytes) -> dict[str, Any]:
    """The fields of a `message` payload; WireError if it is malformed."""
    return _WIRE.decode(message, payload)


# The SPAWN fields by their names in wire/daemon.schema (a flags field by its bits).
_SPAWN_FIELDS = [b.name for f in _WIRE.schema.messages["SPAWN"].fields if f.type.kind == "flags"
                 for b in _WIRE.schema.enums[f.type.ref or ""].entries] + \
                [f.name for f in _WIRE.schema.messages["SPAWN"].fields if f.type.kind != "flags"]


def encode_spawn(spec: SpawnSpec) -> bytes:
    if spec.shell:
        argv = [spec.command]
    elif spec.argv is not None:
        argv = spec.argv
    else:
        try:
            argv = split_command(spec.command)
        except CommandSplitError as e:
            raise DaemonError(f"cannot split command of {spec.name}: {e}") from None
    # A SPAWN field that SpawnSpec has under its schema name goes as it is (so a new field
    # of the schema needs only a SpawnSpec attribute); the others are converted here.
    fields = {name: getattr(spec, name) for name in _SPAWN_FIELDS if hasattr(spec, name)}
    log_path, log_limit, log_keep = spec.output_log or ("", 0, 0)
    fields.update({
        "argv": argv, "env": [f"{k}={v}" for k, v in spec.env.items()], "cwd": spec.cwd or "",
        "rlimits": [{"name": name, "soft": -1 if soft is None else soft,
                     "hard": -1 if hard is None else hard}
                    for name, soft, hard in spec.rlimits],
        "affinity": spec.affinity or [], "log_path": log_path, "log_limit": log_limit,
        "log_keep": log_keep})
    try:
        return _WIRE.encode("SPAWN", fields)
    except WireError as e:
        raise DaemonError(f"invalid spawn spec for {spec.name}: {e}") from None


def process_info(f: Mapping[str, Any]) -> ProcessInfo:
    """A ProcessInfo of a decoded process record (SPAWNED, PROCESS_LIST)."""
    state = STATES.get(int(f["state"]), str(int(f["state"])))
    kind = f["exit_kind"]
    return ProcessInfo(name=f["name"], pid=f["pid"], state=state,
                       exit_code=f["exit_value"] if kind == EXIT_CODE else None,
                       signal=f["exit_value"] if kind == EXIT_SIGNAL else None,
                       started=f["started"], exited=f["exited"] if state == "exited" else None,
                       output_lines=f["lines_kept"], output_total=f["lines_total"])


def transport_code(transport: str) -> int:
    try:
        return TRANSPORTS[transport]
    except KeyError:
        raise DaemonError(f"unknown transport {transport!r} (known: udp, tcp)") from None


def security_code(level: str) -> int:
    try:
        return SECURITY_LEVELS[level]
    except KeyError:
        raise DaemonError(f"unknown security level {level!r} "
                          "(known: none, authenticate, encrypt)") from None


def decode_stream_list(payload: bytes) -> tuple[list[StreamStat], StreamTotals]:
    f = decode("STREAM_LIST", payload)
    streams = [StreamStat(**{**s, "transport": s["transport"].name.lower()})
               for s in f["streams"]]
    return streams, StreamTotals(unknown_stream=f["unknown_stream"], malformed=f["malformed"])


_SAMPLE_HEAD = struct.Struct("<Qq")  # LOGGER_DATA's tail: per sample seq, timestamp_ns, data


def decode_logger_chunk(payload: bytes) -> LoggerChunk:
    f = decode("LOGGER_DATA", payload)
    tail, size = f["samples"], f["message_size"]
    if len(tail) < 4:
        raise WireError("LOGGER_DATA.samples: short payload")
    (count,) = struct.unpack_from("<I", tail)
    per = _SAMPLE_HEAD.size + size
    if len(tail) != 4 + count * per:
        raise WireError(f"LOGGER_DATA.samples: {len(tail) - 4} bytes for {count} samples")
    samples = []
    for pos in range(4, len(tail), per):
        seq, timestamp_ns = _SAMPLE_HEAD.unpack_from(tail, pos)
        samples.append((seq, timestamp_ns, tail[pos + _SAMPLE_HEAD.size:pos + per]))
    return LoggerChunk(message_size=size, layout_hash=f["layout_hash"], md_name=f["md_name"],
                       enabled=f["enabled"], **f["counters"], first_seq=f["first_seq"],
                       last_seq=f["last_seq"], start_seq=f["start_seq"], samples=samples)


def decode_logger_list(payload: bytes) -> LoggerStatus:
    f = decode("LOGGER_LIST", payload)
    topics = [LoggerTopicStatus(
        logger=t["logger"], topic=t["topic"], ring=t["ring"], md_name=t["md_name"],
        enabled=t["enabled"], depth=t["depth"], divisor=t["divisor"], span=t["span_s"],
        message_size=t["message_size"], **t["counters"], last_error=t["last_error"])
        for t in f["topics"]]
    return LoggerStatus(memory_limit=f["memory_limit"], memory_used=f["memory_used"],
                        topics=topics)


def decode_error(payload: bytes) -> tuple[ErrorCode | int, str]:
    try:
        f = decode("ERROR", payload)
    except WireError:
        return ErrorCode.BAD_REQUEST, "malformed error from the daemon"
    code: ErrorCode | int = f["code"]
    if code in ErrorCode._value2member_map_:
        code = ErrorCode(code)
    return code, f["text"]
