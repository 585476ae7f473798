"""The live introspection commands (docs/introspection.md): `topic echo|hz|bw|info`,
`md show`, `service call`.  One implementation for the console (introspect_console.py),
`ln_manager topic|md|service ...` (introspect_cli.py) and the scripting API
(introspect_api.py): each runs with a Context that says how to ask the manager (CONTROL
commands), where its clients connect, where output lines go and when to stop.  Every
failure is a CommandError of one line."""

from __future__ import annotations

import re
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

from ln_generate import MessageDef

from . import values as fmt
from .values import IntrospectError
from .client import READ_SLICE, Sample, TopicReader, load_md, md_class
from .request import RequestTextError, conform, parse
from .stats import PeriodStats, Window, bw_line, hz_line

REPORT_EVERY = 1.0  # seconds between the lines of `topic hz` / `topic bw`


class CommandError(Exception):
    """A command that cannot be carried out: one line."""


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
def topic_info(ctx: Context, name: str) -> dict[str, Any]:
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


def _address(ctx: Context) -> str:
    if not ctx.address:
        raise CommandError("no address of the manager for a client to connect to")
    return ctx.address


def open_reader(ctx: Context, info: dict[str, Any], purpose: str) -> TopicReader:
    from ...errors import LnError

    address = _address(ctx)
    try:
        return TopicReader(address, f"{ctx.client_prefix}_topic_{purpose}", info["name"],
                           info["md_name"], _hash(info["layout_hash"]), info["message_size"])
    except LnError as exc:
        raise _ln_error(f"topic {info['name']!r}: cannot subscribe", exc) from None


def follow(ctx: Context, reader: TopicReader, topic: str, duration: float | None = None,
           on_tick: Callable[[], None] | None = None) -> Iterator[Sample]:
    """The samples `reader` gets until ctx.stop is set or `duration` seconds passed;
    on_tick runs every REPORT_EVERY seconds meanwhile (the pace of printing only)."""
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
        wait = READ_SLICE if duration is None else min(READ_SLICE, start + duration - now)
        try:
            sample = reader.read(max(wait, 0.0))
        except LnError as exc:
            raise _ln_error(f"topic {topic!r}: reading failed", exc) from None
        if sample is not None:
            yield sample


def echo_records(ctx: Context, name: str, n: int | None = None,
                 duration: float | None = None, field_path: str | None = None,
                 on_record: Callable[[Sample, Any], None] | None = None) -> list[Any]:
    """Follow topic `name` for `n` samples (or `duration` seconds, or until ctx.stop),
    decoding each (only the value at `field_path`, if given).  With on_record, calls
    on_record(sample, value) for each and returns []; else returns their records
    (introspect.sample_record)."""
    info = topic_info(ctx, name)
    md = topic_layout(info)
    path = None
    if field_path is not None:
        try:
            path = fmt.parse_path(field_path)
            fmt.check_path(md.struct, path)
        except IntrospectError as exc:
            raise CommandError(f"topic {name!r}: {exc}") from None
    kept: list[Any] = []
    count = 0
    with open_reader(ctx, info, "echo") as reader:
        for sample in follow(ctx, reader, name, duration):
            value = fmt.decode(md.struct, sample.data)
            if path is not None:
                value = fmt.select(value, path)
            if on_record is not None:
                on_record(sample, value)
            else:
                kept.append(fmt.sample_record(sample.seq, sample.timestamp_ns, value,
                                              field_path))
            count += 1
            if n is not None and count >= n:
                break
    return kept


def echo(ctx: Context, args: dict[str, Any]) -> None:
    field_path = args["field"]

    def show(sample: Sample, value: Any) -> None:
        if args["json"]:
            ctx.say(fmt.json_line(fmt.sample_record(sample.seq, sample.timestamp_ns, value,
                                                    field_path)))
            return
        lines = fmt.format_any(value, args["full"])
        if field_path is None or fmt.is_block(value):
            ctx.say(fmt.header(sample.seq, sample.timestamp_ns))
        for line in lines:
            ctx.say(line)

    echo_records(ctx, args["name"], args["n"], args["duration"], field_path, show)


def measure(ctx: Context, info: dict[str, Any], n: int | None, duration: float | None,
            window: int, report: Callable[[PeriodStats | None, int], None] | None = None,
            purpose: str = "hz") -> PeriodStats | None:
    """Follow the topic of `info` (topic_info) into a Window of `window` samples until `n`
    samples were taken, `duration` passed or ctx.stop; report(stats, new samples) every
    REPORT_EVERY seconds.  A first sample published before subscribing (the newest one
    then) is not taken.  The final statistics (None for fewer than two samples)."""
    win = Window(window)
    seen = 0

    def tick() -> None:
        nonlocal seen
        if report is not None:
            report(win.stats(), win.received - seen)
        seen = win.received

    with open_reader(ctx, info, purpose) as reader:
        first = True
        for sample in follow(ctx, reader, info["name"], duration, tick):
            if first and sample.timestamp_ns < reader.subscribed_ns:
                first = False
                continue
            first = False
            win.add(sample.seq, sample.timestamp_ns)
            if n is not None and win.received >= n:
                break
    return win.stats()


def _rate(ctx: Context, args: dict[str, Any], line: Callable[[PeriodStats, int], str],
          purpose: str) -> None:
    info = topic_info(ctx, args["name"])
    size = info["message_size"]

    def report(stats: PeriodStats | None, new: int) -> None:
        if not new:
            ctx.say("no new samples")
        elif stats is None:
            ctx.say("waiting for a second sample")
        else:
            ctx.say(line(stats, size))

    stats = measure(ctx, info, args["n"], args["duration"], args["window"], report, purpose)
    if args["n"] is not None or args["duration"] is not None:
        ctx.say("no rate: fewer than 2 samples" if stats is None else line(stats, size))


def hz(ctx: Context, args: dict[str, Any]) -> None:
    _rate(ctx, args, lambda stats, _size: hz_line(stats), "hz")


def bw(ctx: Context, args: dict[str, Any]) -> None:
    _rate(ctx, args, bw_line, "bw")


def info(ctx: Context, args: dict[str, Any]) -> None:
    result = topic_info(ctx, args["name"])
    if args["json"]:
        import json

        for line in json.dumps(result, indent=2).splitlines():
            ctx.say(line)
    else:
        for line in fmt.info_lines(result):
            ctx.say(line)


# ---- message definitions -----------------------------------------------------------------
def md_text(ctx: Context, name: str, recursive: bool = False) -> str:
    """The md's text as `md show` prints it: the file; with `recursive` each md it uses
    after it, every one under a `# ==== NAME: PATH` line."""
    result = ctx.control("md_show", name=name, recursive=recursive)
    if not recursive:
        return str(result["mds"][0]["text"])
    parts = []
    for md in result["mds"]:
        text = md["text"] if md["text"].endswith("\n") or not md["text"] else md["text"] + "\n"
        parts.append(f"# ==== {md['name']}: {md['path']}\n{text}")
    return "".join(parts)


def md_show(ctx: Context, args: dict[str, Any]) -> None:
    for line in md_text(ctx, args["name"], args["recursive"]).removesuffix("\n").split("\n"):
        ctx.say(line)


# ---- services ----------------------------------------------------------------------------
def service_call_values(ctx: Context, name: str, request: dict[str, Any] | str,
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


def service_call(ctx: Context, args: dict[str, Any]) -> None:
    response = service_call_values(ctx, args["name"], args["request"], args["timeout"])
    if args["json"]:
        ctx.say(fmt.json_line(response))
    else:
        for line in fmt.format_block(response, args["full"]) or ["{}"]:
            ctx.say(line)


COMMANDS: dict[tuple[str, str], Callable[[Context, dict[str, Any]], None]] = {
    ("topic", "echo"): echo, ("topic", "hz"): hz, ("topic", "bw"): bw,
    ("topic", "info"): info, ("md", "show"): md_show, ("service", "call"): service_call,
}
FOLLOWING = {("topic", "echo"), ("topic", "hz"), ("topic", "bw")}  # run until stopped


def run(ctx: Context, key: tuple[str, str], args: dict[str, Any]) -> None:
    """Run one parsed command (introspect_args.parse); CommandError when it fails."""
    COMMANDS[key](ctx, args)
