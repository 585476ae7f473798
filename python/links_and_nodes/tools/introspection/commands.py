"""The live introspection commands (docs/introspection.md): `topic echo|hz|bw`, `md show`,
`service call` and what the bridges and the web UI use of them.  Each runs in a client of the
manager with a context (tools/commands/local.py Local, or Context) that says how to ask the
manager (CONTROL commands), where its libln clients connect and when to stop; `topic echo`,
`hz` and `bw` yield rows as they come (their text is views.py's).  Every failure is a
CommandError of one line."""

from __future__ import annotations

import re
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any, Protocol

from ln_generate import MessageDef

from ..commands import ControlError
from . import values as fmt
from .client import READ_SLICE, TopicReader, load_md, md_class
from .request import RequestTextError, conform, parse
from .stats import Window
from .values import IntrospectError

REPORT_EVERY = 1.0  # seconds between the rows of `topic hz` / `topic bw`


class CommandError(ControlError):
    """A command that cannot be carried out: one line."""


class Asks(Protocol):
    """What the commands use of their context (Local, Context)."""

    control: Callable[..., dict[str, Any]]
    address: str
    stop: threading.Event
    client_prefix: str


@dataclass
class Context:
    """control(op, **args) -> result dict (CommandError when refused); address: the
    manager's HOST:PORT for libln clients; say: one output line; stop: set to end a
    command that follows a topic."""

    control: Callable[..., dict[str, Any]]
    address: str
    say: Callable[[str], None]
    stop: threading.Event = field(default_factory=threading.Event)
    client_prefix: str = "ln"


def _hash(text: str) -> int:
    return int(text, 16)


def _md(name: str, dirs: list[str], what: str) -> MessageDef:
    try:
        return load_md(name, dirs)
    except IntrospectError as exc:
        raise CommandError(f"{what}: cannot load its md {name!r}: {exc}") from None


def _ln_error(what: str, exc: Exception) -> CommandError:
    return CommandError(f"{what}: {exc}")


# ---- topics ------------------------------------------------------------------------------
def topic_info(ctx: Asks, name: str) -> dict[str, Any]:
    info = ctx.control("topic_info", name=name)
    info.pop("ok", None)
    return info


def topic_layout(info: dict[str, Any]) -> MessageDef:
    """The md of a topic (from topic_info), checked against the topic's layout."""
    what = f"topic {info['name']!r}"
    md = _md(info["md_name"], info["md_dirs"], what)
    if md.kind != "message":
        raise CommandError(f"{what}: md {md.name!r} is a {md.kind}, not a message")
    if (md.layout_hash, md.struct.size) != (_hash(info["layout_hash"]), info["message_size"]):
        raise CommandError(
            f"{what}: layout mismatch: md {md.name!r} found here ({md.path}) has hash "
            f"0x{md.layout_hash:016x} and {md.struct.size} bytes, the topic has hash "
            f"{info['layout_hash']} and {info['message_size']} bytes")
    return md


def _address(ctx: Asks) -> str:
    if not ctx.address:
        raise CommandError("no address of the manager for a client to connect to")
    return ctx.address


def open_reader(ctx: Asks, info: dict[str, Any], purpose: str) -> TopicReader:
    from ...errors import LnError

    address = _address(ctx)
    try:
        return TopicReader(address, f"{ctx.client_prefix}_topic_{purpose}", info["name"],
                           info["md_name"], _hash(info["layout_hash"]), info["message_size"])
    except LnError as exc:
        raise _ln_error(f"topic {info['name']!r}: cannot subscribe", exc) from None


def follow(ctx: Asks, reader: TopicReader, topic: str, duration: float | None = None,
           on_tick: Callable[[], None] | None = None, ticks: bool = False) -> Iterator[Any]:
    """The samples `reader` gets until ctx.stop is set or `duration` seconds passed;
    on_tick runs every REPORT_EVERY seconds meanwhile (the pace of printing only), and with
    `ticks` None is yielded right after it."""
    from ...errors import LnError

    start = time.monotonic()
    next_tick = start + REPORT_EVERY
    while not ctx.stop.is_set():
        now = time.monotonic()
        if duration is not None and now - start >= duration:
            return
        if on_tick is not None and now >= next_tick:
            on_tick()
            while next_tick <= now:
                next_tick += REPORT_EVERY
            if ticks:
                yield None
        wait = READ_SLICE if duration is None else min(READ_SLICE, start + duration - now)
        try:
            sample = reader.read(max(wait, 0.0))
        except LnError as exc:
            raise _ln_error(f"topic {topic!r}: reading failed", exc) from None
        if sample is not None:
            yield sample


def echo_records(ctx: Asks, name: str, n: int | None = None,
                 duration: float | None = None,
                 field_path: str | None = None) -> Iterator[dict[str, Any]]:
    """Follow topic `name` for `n` samples (or `duration` seconds, or until ctx.stop),
    yielding the record of each (values.sample_record; only the value at `field_path`, if
    given)."""
    info = topic_info(ctx, name)
    md = topic_layout(info)
    path = None
    if field_path is not None:
        try:
            path = fmt.parse_path(field_path)
            fmt.check_path(md.struct, path)
        except IntrospectError as exc:
            raise CommandError(f"topic {name!r}: {exc}") from None
    count = 0
    with open_reader(ctx, info, "echo") as reader:
        for sample in follow(ctx, reader, name, duration):
            value = fmt.decode(md.struct, sample.data)
            if path is not None:
                value = fmt.select(value, path)
            yield fmt.sample_record(sample.seq, sample.timestamp_ns, value, field_path)
            count += 1
            if n is not None and count >= n:
                break


def echo(ctx: Asks, args: dict[str, Any]) -> Iterator[dict[str, Any]]:
    """`topic echo`: a record of each sample as it comes."""
    return echo_records(ctx, args["name"], args["n"], args["duration"], args["field"])


def rates(ctx: Asks, args: dict[str, Any], purpose: str) -> Iterator[dict[str, Any]]:
    """`topic hz` / `topic bw`: follow the topic into a Window of args["window"] samples until
    -n samples were taken, --duration passed or ctx.stop, with a row every REPORT_EVERY
    seconds {"stats" (None for fewer than two samples), "new" (samples since the last row),
    "message_size", "final": false} and with -n or --duration a last one over the whole
    run ("final": true).  A first sample published before subscribing (the newest one
    then) is not taken."""
    info = topic_info(ctx, args["name"])
    size = info["message_size"]
    n, duration = args["n"], args["duration"]
    win = Window(args["window"])
    seen = 0
    ticked: list[bool] = []

    def row(final: bool) -> dict[str, Any]:
        stats = win.stats()
        return {"stats": stats.as_dict() if stats is not None else None,
                "new": win.received - (0 if final else seen), "message_size": size,
                "final": final}

    with open_reader(ctx, info, purpose) as reader:
        first = True
        for sample in follow(ctx, reader, info["name"], duration, lambda: ticked.append(True),
                             ticks=True):
            if ticked:
                ticked.clear()
                yield row(False)
                seen = win.received
            if sample is None:
                continue
            if first and sample.timestamp_ns < reader.subscribed_ns:
                first = False
                continue
            first = False
            win.add(sample.seq, sample.timestamp_ns)
            if n is not None and win.received >= n:
                break
    if n is not None or duration is not None:
        yield row(True)


def hz(ctx: Asks, args: dict[str, Any]) -> Iterator[dict[str, Any]]:
    return rates(ctx, args, "hz")


def bw(ctx: Asks, args: dict[str, Any]) -> Iterator[dict[str, Any]]:
    return rates(ctx, args, "bw")


# ---- message definitions -----------------------------------------------------------------
def md_text(result: dict[str, Any]) -> str:
    """The text `md show` prints of the manager's md_show answer: the file; with
    "recursive" each md it uses after it, every one under a `# ==== NAME: PATH` line."""
    if not result.get("recursive"):
        return str(result["mds"][0]["text"])
    parts = []
    for md in result["mds"]:
        text = md["text"] if md["text"].endswith("\n") or not md["text"] else md["text"] + "\n"
        parts.append(f"# ==== {md['name']}: {md['path']}\n{text}")
    return "".join(parts)


# ---- services ----------------------------------------------------------------------------
def service_call_values(ctx: Asks, name: str, request: dict[str, Any] | str,
                        timeout: float) -> dict[str, Any]:
    """Call service `name` with `request` (plain values or request text); its response."""
    from ...errors import LnError

    svc = ctx.control("service_info", name=name)
    what = f"service {name!r}"
    md = _md(svc["md_name"], svc["md_dirs"], what)
    if md.kind != "service":
        raise CommandError(f"{what}: md {md.name!r} is a {md.kind}, not a service")
    if md.layout_hash != _hash(svc["layout_hash"]):
        raise CommandError(f"{what}: layout mismatch: md {md.name!r} found here ({md.path}) "
                           f"has hash 0x{md.layout_hash:016x}, the provider registered "
                           f"{svc['layout_hash']}")
    try:
        values = parse(request) if isinstance(request, str) else request
        values = conform(md.sections["request"], values)
    except RequestTextError as exc:
        raise CommandError(str(exc)) from None
    cls = md_class(md.name, svc["md_dirs"])
    from .client import call_service

    try:
        response = call_service(_address(ctx), f"{ctx.client_prefix}_service_call", name, cls,
                                values, timeout)
    except LnError as exc:
        if exc.name == "ESERVICE":
            detail = exc.detail or str(exc)
            match = re.match(r'service ".*?" \(provider "(.*?)"\): (.*)\Z', detail, re.S)
            if match:
                what, detail = f"{what} (provider {match.group(1)!r})", match.group(2)
            raise CommandError(f"{what} answered with an error: {detail}") from None
        raise _ln_error(f"{what}: the call failed", exc) from None
    return fmt.tidy(md.sections["response"], response)


def service_call(ctx: Asks, args: dict[str, Any]) -> dict[str, Any]:
    """`service call`: {"response": the provider's answer}."""
    request = args["request"]
    return {"response": service_call_values(ctx, args["name"], request or {},
                                            args["timeout"])}
