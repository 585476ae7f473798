"""Live introspection in the command table (docs/introspection.md): `topic echo|hz|bw|info`,
`md show`, `service call`.  Answered here, from what the manager knows:

    topic_info {"name"}             md, layout, ring, publishers and subscribers with their
                                    clients and hosts, transports, forwarding rates
    service_info {"name"}           the service as `services` lists it, plus md_dirs
    md_show {"name", "recursive"}   the md's text (and of the mds it uses), its file
    md_layout {"name"}              the md's layout hash, signature and field names, for
                                    clients that pack samples at run time (docs/matlab.md)

`topic echo|hz|bw` and `service call` run in the client (tools/introspection/commands.py),
with their own libln client; echo, hz and bw stream.

Each answer carries `md_dirs`, the manager's md search path (the configuration's
`add_message_definition_dir` directories, then the built-in ones and the manager's
LN_MESSAGE_DEFINITION_DIRS), so a client decodes with the mds the system was built with.

Registering is light (the table is read by `ln_manager --help`): what the client side runs
(ln_generate, the libln subscriber) is imported when it runs, what the manager's handlers
use when they answer."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from ...tools.commands import Arg, Command, Verb, register
from ...tools.introspection import DEFAULT_TIMEOUT, views
from ...tools.introspection.stats import DEFAULT_WINDOW

if TYPE_CHECKING:
    from ln_generate import Struct

    from ..registry.core import Core
    from ..registry.model import Client, Port, Topic


class Control(Protocol):
    """What these handlers use of the manager's Control (frontends/control.py)."""

    core: Core
    scheduler: Any  # the Scheduler of a configuration, or None
    network_view: Any  # the hosts of a multi-host configuration, or None


def _error(text: str) -> Exception:
    from ...tools.commands import ControlError

    return ControlError(text)


def md_dirs(control: Control) -> list[str]:
    """The manager's md search path: the configuration's directories (its own, then those
    of its processes), then the default ones."""
    from ln_generate import default_md_dirs

    dirs: list[str] = []
    config = getattr(control.scheduler, "config", None)
    if config is not None:
        dirs += config.message_definition_dirs
        for proc in config.processes.values():
            dirs += proc.message_definition_dirs
    return [str(d) for d in default_md_dirs(list(dict.fromkeys(dirs)))]


# ---- topics ------------------------------------------------------------------------------
def _host(control: Control, client: Client) -> str:
    hosts = getattr(control.core, "hosts", None)
    if hosts is not None:
        return str(hosts.host_label(client))
    return client.host_id.partition("/")[0] or "?"


def _port(control: Control, port: Port) -> dict[str, Any]:
    from ... import transports
    from ...tools import protocol as p
    from ..registry.model import PortKind

    c = port.client
    entry: dict[str, Any] = {"client": c.name, "client_id": c.id, "pid": c.pid,
                             "host": _host(control, c), "host_id": c.host_id,
                             "address": c.address, "port": port.id, "md_name": port.md_name,
                             "buffers": port.buffers}
    if port.kind is PortKind.PUBLISHER:
        entry["wait_for_subscribers"] = bool(port.flags & p.PUBLISH_WAIT_FOR_SUBSCRIBERS)
    else:
        entry["mode"] = "latest" if port.buffers == 1 else "queued"
        entry["reader"] = port.reader_index
        entry["asks"] = transports.asked(port.flags, udp_flag=p.SUBSCRIBE_UDP,
                                         tcp_flag=p.SUBSCRIBE_TCP) or ""
    return entry


def _rings(control: Control, topic: Topic) -> list[dict[str, Any]]:
    core = control.core
    hosts = getattr(core, "hosts", None)
    every = hosts.all_rings() if hosts is not None else [core.local]
    out = []
    for rings in every:
        if not rings.has(topic.id):
            continue
        host = rings.host or (hosts.local_name() if hosts is not None else "local")
        names = core.segments.names(topic.id) if rings is core.local else [
            rings.current(topic.id)]
        out.append({"host": host, "segment": rings.current(topic.id), "generations": names})
    return out


async def topic_info(control: Control, command: dict[str, Any]) -> dict[str, Any]:
    name = command["name"]
    topic = control.core.registry.topics.get(name)
    if topic is None:
        raise _error(f"no topic {name!r}")
    from ... import transports
    from ..registry.model import PortKind
    from ..registry.segments import ring_segment_size

    ports = sorted(topic.ports.values(), key=lambda port: port.id)
    publishers = [_port(control, port) for port in ports if port.kind is PortKind.PUBLISHER]
    subscribers = [_port(control, port) for port in ports
                   if port.kind is PortKind.SUBSCRIBER]
    view = control.network_view
    streams = [s for s in view.stream_listing()["streams"] if s["topic"] == name] \
        if view is not None else []
    origin = {pub["host"] for pub in publishers}
    for sub in subscribers:
        if not publishers:
            sub["transport"] = "-"
        elif sub["host"] in origin:
            sub["transport"] = transports.SHM
        else:
            via = [s["transport"] for s in streams if s["dst"] == sub["host"]]
            sub["transport"] = f"forwarded {via[0]}" if via else "forwarded (no stream)"
    return {"name": topic.name, "id": topic.id, "md_name": topic.md_name,
            "layout_hash": f"0x{topic.layout_hash:016x}", "message_size": topic.message_size,
            "slots": topic.slots,
            "ring_bytes": int(ring_segment_size(topic.message_size, topic.slots)),
            "published": await control.core.topic_published(name),
            "adopted": topic.held, "rings": _rings(control, topic),
            "publishers": publishers, "subscribers": subscribers,
            "streams": [{k: s[k] for k in ("src", "dst", "transport", "msgs_per_s",
                                           "bytes_per_s", "drops", "error")}
                        for s in streams],
            "md_dirs": md_dirs(control)}


# ---- services ----------------------------------------------------------------------------
async def service_info(control: Control, command: dict[str, Any]) -> dict[str, Any]:
    name = command["name"]
    for service in control.core.services():
        if service["name"] == name:
            return {**service, "layout_hash": f"0x{service['layout_hash']:016x}",
                    "md_dirs": md_dirs(control)}
    raise _error(f"no service {name!r}")


# ---- message definitions -----------------------------------------------------------------
async def md_show(control: Control, command: dict[str, Any]) -> dict[str, Any]:
    from ln_generate import MdError, MdRegistry
    from ln_generate.lookup import LookupError_, find

    from ...tools.introspection.client import md_error_text

    name, recursive = command["name"], command["recursive"]
    dirs = md_dirs(control)
    paths = [Path(d) for d in dirs]
    try:
        _, _, path = find(name, paths)
    except LookupError_ as exc:
        raise _error(str(exc)) from None
    entries = [{"name": name, "path": str(path), "text": _read(path)}]
    if recursive:
        try:
            md = MdRegistry(paths).load(name)
        except MdError as exc:
            raise _error(f"md {name!r}: {md_error_text(exc)}") from None
        entries += [{"name": dep.name, "path": str(dep.path), "text": _read(dep.path)}
                    for dep in md.dependencies()]
    return {"name": name, "path": str(path), "mds": entries, "md_dirs": dirs,
            "recursive": recursive}


async def md_layout(control: Control, command: dict[str, Any]) -> dict[str, Any]:
    from ln_generate import MdError, MdRegistry
    from ln_generate.layout import layout_hash, md_signature

    from ...tools.introspection.client import md_error_text

    name = command["name"]
    dirs = md_dirs(control)
    try:
        md = MdRegistry([Path(d) for d in dirs]).load(name)
    except MdError as exc:
        raise _error(f"md {name!r}: {md_error_text(exc)}") from None
    sections = [{"name": section, "size": struct.size, "names": ",".join(_names(struct))}
                for section, struct in md.sections.items()]
    return {"name": name, "kind": md.kind, "layout_hash": f"0x{layout_hash(md):016x}",
            "signature": md_signature(md), "sections": sections, "md_dirs": dirs}


def _names(struct: Struct) -> list[str]:
    """Field names in pre-order, one per field of the signature (a dynamic field's count and
    pointer are one field): a nested md's name, then its own fields' names."""
    out: list[str] = []
    for f in struct.fields:
        out.append(f.name)
        if f.is_nested:
            out += _names(f.type)  # type: ignore[arg-type]
    return out


def _read(path: Path) -> str:
    try:
        return path.read_bytes().decode("utf-8", "replace")
    except OSError as exc:
        raise _error(f"cannot read {path}: {exc.strerror or exc}") from None


# ---- the table ---------------------------------------------------------------------------
def _run(name: str) -> Callable[..., Any]:
    """The function `name` of tools/introspection/commands.py (what runs in the client),
    imported when it is called."""
    def call(*args: Any) -> Any:
        from ...tools.introspection import commands as run

        return getattr(run, name)(*args)

    call.__name__ = call.__qualname__ = name
    return call


def _seconds(what: str, help_text: str, default: float | None = None) -> Arg:
    option = "--" + what
    return Arg(what, "float", help_text, default=default, low=1e-6, high=1e9, metavar="S",
               error=option + ": {value!r} is not a number of seconds above 0")


_NAME = Arg("name", "str", "its name", required=True, positional=True, nonempty=True)
_N = Arg("n", "int", "stop after N samples", low=1, flag="-n", metavar="N",
         error="-n: {value!r} is not a whole number of at least 1")
_WINDOW = Arg("window", "int", "statistics over the newest N samples",
              default=DEFAULT_WINDOW, low=2, metavar="N",
              error="--window: {value!r} is not a whole number of at least 2")
_JSON = Arg("json", "bool", "print JSON", default=False, where="text")
_FULL = Arg("full", "bool", "every value of long arrays", default=False, where="text")


def _echo_args(name: str, n: int | None = 1, field: str | None = None,
               timeout: float | None = DEFAULT_TIMEOUT) -> dict[str, Any]:
    return {"name": name, "n": n, "field": field, "duration": timeout}


def _rate_args(name: str, duration: float | None = 2.0, n: int | None = None,
               window: int = DEFAULT_WINDOW) -> dict[str, Any]:
    if duration is None and n is None:
        raise ValueError("give a duration or a number of samples n")
    return {"name": name, "duration": duration, "n": n, "window": window}


def _service_request(value: Any) -> Any:
    from ...tools.commands import ArgError

    if not isinstance(value, dict | str):
        raise ArgError('"request" must be an object of field values or request text')
    return value


def _rate(name: str, help_text: str, handler: Any, bandwidth: bool, doc: str) -> Command:
    word = name.removeprefix("topic_")
    return Command(
        name, help_text, "topics", None,
        (_NAME, _seconds("duration", "stop after S seconds"), _N, _WINDOW), phrase=f"topic {word}",
        result="rows: [{stats: {samples, periods, missed, span_s, rate_hz, mean_s, min_s, "
               "max_s, std_s} or null, new, message_size, final}]",
        run=handler, streams=True, missing_usage=True,
        console_format=views.bw_lines if bandwidth else views.hz_lines,
        script_args=_rate_args, script_doc=doc,
        script_result=lambda rows: views.rate_result(rows, bandwidth))


register(
    Command("topic_echo", "print samples decoded by the topic's md", "topics", None,
            (_NAME, _N, _seconds("duration", "stop after S seconds"),
             Arg("field", "str", "only this field (a path: q[2], target.position)",
                 metavar="F", nullable=True),
             _JSON, _FULL),
            phrase="topic echo", run=_run("echo"), streams=True, missing_usage=True,
            result="rows: [{seq, publish_time, publish_time_ns, data, field}]",
            console_format=views.echo_lines, script_args=_echo_args,
            script_doc="The next `n` samples of topic `name` (fewer if `timeout` seconds pass "
                       "first), each {\"seq\", \"publish_time\" (s), \"publish_time_ns\", "
                       "\"data\"} with data the decoded sample, or only the value at `field` "
                       "(e.g. \"target.position[2]\"; then also \"field\")."),
    _rate("topic_hz", "rate and period statistics from the publish timestamps, every second",
          _run("hz"), False,
          "Rate statistics of topic `name` over `duration` seconds or `n` samples (whichever "
          "ends first): samples, periods, missed, span_s, rate_hz, mean_s, min_s, max_s, "
          "std_s (fewer than two samples: rate_hz 0, the rest None)."),
    _rate("topic_bw", "bytes per second (message size x rate), every second", _run("bw"), True,
          "topic_hz's statistics plus message_size and bytes_per_s (size x rate)."),
    Command("topic_info", "md, layout, ring, publishers and subscribers with clients, hosts, "
            "transports", "topics", topic_info,
            (_NAME, Arg("json", "bool", "print JSON", default=False, where="console")),
            result="name, id, md_name, layout_hash, message_size, slots, ring_bytes, "
                   "published, adopted, rings, publishers, subscribers, streams, md_dirs",
            phrase="topic info", missing_usage=True, console_format=views.info_view,
            script_doc="What the manager knows of topic `name`: md_name, layout_hash "
                       "(\"0x%016x\"), message_size, slots, ring_bytes, published (samples "
                       "so far), rings (host, segment, generations), publishers and "
                       "subscribers (client, pid, host, port, buffers; mode, reader and "
                       "transport of subscribers), streams (forwarding to other hosts with "
                       "rates), md_dirs (the manager's md search path)."),
    Command("service_info", "a service as `services` lists it, plus md_dirs", "services",
            service_info, (_NAME,), result="name, provider, md_name, layout_hash, calls, "
            "errors, ..., md_dirs", console=False, cli=False),
    Command("md_show", "the text of a message definition (with -r also of the mds it uses)",
            "topics", md_show,
            (_NAME, Arg("recursive", "bool", "also the mds it uses", default=False,
                        short="-r")),
            result="name, path, mds: [{name, path, text}], md_dirs, recursive",
            phrase="md show", missing_usage=True, console_format=views.md_lines,
            script_result=_run("md_text"),
            script_doc="The text of md `name` from the manager's md search path; with "
                       "`recursive` also of every md it uses, each under a `# ==== NAME: "
                       "PATH` line."),
    Command("md_layout", "the layout hash, signature and field names of a message definition",
            "topics", md_layout, (_NAME,),
            result="name, kind, layout_hash, signature, sections: [{name, size, names}], "
                   "md_dirs", console=False, cli=False,
            script_doc="What a client that packs samples at run time needs of md `name` "
                       "(docs/matlab.md): layout_hash (\"0x%016x\"), the signature of "
                       "ln_generate and per section its struct size and its field names in "
                       "pre-order, comma-separated."),
    Command("service_call", "call a service with REQUEST fields ('a: 1, b: [1, 2], name: "
            "\"x\"' or JSON)", "services", None,
            (_NAME, Arg("request", "json", "the request: field values or request text",
                        positional=True, rest="join", check=_service_request),
             _JSON, _FULL, _seconds("timeout", "the longest the call may take", DEFAULT_TIMEOUT)),
            phrase="service call", run=_run("service_call"), missing_usage=True,
            changes_state=True, result="response", console_format=views.response_lines,
            script_result=lambda row: row["response"],
            script_doc="Call service `name` once: `request` as a dict of request fields "
                       "(nested dicts, lists) or request text ('a: 1, b: [1, 2]' or JSON); "
                       "the response as a dict.  An error response raises ManagerError with "
                       "the provider's text."),
    Verb("topic", "samples, rates and what the manager knows of a topic", "introspection",
         choose="command"),
    Verb("md", "a message definition's text", "introspection", choose="command"),
    Verb("service", "call a service", "introspection", choose="command"),
)
