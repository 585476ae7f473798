"""The manager's side of live introspection (docs/introspection.md): CONTROL commands that
describe a topic, a service or a message definition from what the manager knows.

    topic_info {"name"}             md, layout, ring, publishers and subscribers with their
                                    clients and hosts, transports, forwarding rates
    service_info {"name"}           the service as `services` lists it, plus md_dirs
    md_show {"name", "recursive"}   the md's text (and of the mds it uses), its file

Each answer carries `md_dirs`, the manager's md search path (the configuration's
`add_message_definition_dir` directories, then the built-in ones and the manager's
LN_MESSAGE_DEFINITION_DIRS), so a client decodes with the mds the system was built with."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from ... import transports
from ..registry import protocol as p
from ..frontends.commands import Arg, Command, Verb, register
from ..registry.model import Client, Port, PortKind, Topic

if TYPE_CHECKING:
    from ..frontends.control import Control


def _error(text: str) -> Exception:
    from ..frontends.control import ControlError

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

    from .client import md_error_text

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
    return {"name": name, "path": str(path), "mds": entries, "md_dirs": dirs}


def _read(path: Path) -> str:
    try:
        return path.read_bytes().decode("utf-8", "replace")
    except OSError as exc:
        raise _error(f"cannot read {path}: {exc.strerror or exc}") from None


# ---- the table ---------------------------------------------------------------------------
async def _console(console: Any, words: list[str]) -> None:
    from .console import execute

    await execute(console, words)


def _cli(argv: list[str]) -> int:
    from .cli import main

    return main(argv)


def _verb(name: str, help_text: str, words: tuple[str, ...]) -> Verb:
    from .args import SPECS

    usage = tuple(line for key, spec in SPECS.items() if key[0] == name
                  for line in (spec.usage, "    " + spec.text))
    return Verb(name, help_text, "introspection", usage,
                lambda console, rest: _console(console, [name, *rest]), _cli, words)


_NAME = Arg("name", "str", "its name", required=True, positional=True, nonempty=True)
register(
    Command("topic_info", "md, layout, ring, publishers and subscribers with their clients "
            "and hosts, transports, forwarding rates", "topics", topic_info, (_NAME,),
            result="name, id, md_name, layout_hash, message_size, slots, ring_bytes, "
                   "published, adopted, rings, publishers, subscribers, streams, md_dirs",
            console=False, cli=False,
            script_doc="What the manager knows of topic `name`: md_name, layout_hash "
                       "(\"0x%016x\"), message_size, slots, ring_bytes, published (samples "
                       "so far), rings (host, segment, generations), publishers and "
                       "subscribers (client, pid, host, port, buffers; mode, reader and "
                       "transport of subscribers), streams (forwarding to other hosts with "
                       "rates), md_dirs (the manager's md search path)."),
    Command("service_info", "a service as `services` lists it, plus md_dirs", "services",
            service_info, (_NAME,), result="name, provider, md_name, layout_hash, calls, "
            "errors, ..., md_dirs", console=False, cli=False),
    Command("md_show", "a message definition's text (recursive: and the mds it uses)",
            "topics", md_show,
            (_NAME, Arg("recursive", "bool", "also the mds it uses", default=False,
                        flag="-r")),
            result="name, path, mds: [{name, path, text}], md_dirs", console=False,
            cli=False),
    _verb("topic", "samples, rates and what the manager knows of a topic",
          ("echo", "hz", "bw", "info")),
    _verb("md", "a message definition's text", ("show",)),
    _verb("service", "call a service", ("call",)),
)
