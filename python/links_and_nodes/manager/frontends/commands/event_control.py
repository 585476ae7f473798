"""The manager's side of events (docs/events.md): which handlers are connected to which event,
with their connect structs, as CONTROL commands.

    event_connect {"event", "service", "md_name", "layout_hash", "signature", "connect"}
        a handler's libln, right after registering the handler's service
        "ln_event/EVENT/CLIENT.N": its connect struct (wire form, hex); again after a
        manager restart
    events {"name"?}
        every event with connected handlers (or just `name`): md, layout hash, signature
        and its handlers (service, client, host, connect, call counts), by service name

The connect struct belongs to the registered service: when the service goes (unregistered,
its client gone) the handler is gone, and a service registered anew under the name has no
connect struct until its libln sends one.  Nothing is kept across a manager restart; the
handlers' libln registers everything again."""

from __future__ import annotations

import re
import weakref
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ....naming import topic_name_problem
from ....tools.commands.spec import Arg, ArgError, Command
from ....tools.commands.table import register

if TYPE_CHECKING:
    from ...registry.services import Service
    from ..control import Control

SERVICE_PREFIX = "ln_event/"
MAX_EVENT_NAME = 160  # bytes (LN_EVENT_MAX_NAME)
MAX_CONNECT = 1024  # bytes of a connect struct in wire form (LN_EVENT_MAX_CONNECT_SIZE)
MAX_HANDLERS = 256  # per event (LN_EVENT_MAX_HANDLERS)
_HEX = re.compile(r"(?:[0-9a-fA-F]{2})*\Z")


@dataclass(frozen=True)
class Connection:
    """What a handler stated when it connected."""

    event: str
    md_name: str
    layout_hash: int
    signature: str
    connect: str  # hex of the wire form


def _connections(control: Control) -> weakref.WeakKeyDictionary[Service, Connection]:
    """The handlers connected through `control`, by their service."""
    return control.event_connections


def _error(text: str, code: str = "") -> Exception:
    from ....tools.commands import ControlError

    return ControlError(text, code)


def _event_name(name: str) -> str:
    problem = topic_name_problem(name, "event")
    if problem is None and len(name.encode()) > MAX_EVENT_NAME:
        problem = f"event name of {len(name.encode())} bytes, must be 1..{MAX_EVENT_NAME}"
    if problem:
        raise ArgError(problem, "EINVAL")
    return name


def _hex(text: str) -> str:
    try:
        int(text, 16)
    except ValueError:
        raise ArgError('"layout_hash" must be a hex number', "EINVAL") from None
    return text


def _live(control: Control,
          connections: weakref.WeakKeyDictionary[Service, Connection]
          ) -> list[tuple[Service, Connection]]:
    """Connected handlers whose service is still the registered one, by service name."""
    registered = control.core.service_registry.by_name
    return sorted(((s, c) for s, c in list(connections.items())
                   if registered.get(s.name) is s), key=lambda sc: sc[0].name)


async def event_connect(control: Control, command: dict[str, Any]) -> dict[str, Any]:
    connections = _connections(control)
    event, name, md_name = command["event"], command["service"], command["md_name"]
    signature, connect = command["signature"], command["connect"]
    layout_hash = int(command["layout_hash"], 16)
    prefix = f"{SERVICE_PREFIX}{event}/"
    if not name.startswith(prefix) or "/" in name[len(prefix):] or name == prefix:
        raise _error(f"{name!r} is not the name of a handler of event {event!r} "
                     f"({prefix}CLIENT.N)", "EINVAL")
    if not _HEX.match(connect) or len(connect) > 2 * MAX_CONNECT:
        raise _error(f"event {event!r}: the connect struct must be hex of at most "
                     f"{MAX_CONNECT} bytes", "EINVAL")
    service = control.core.service_registry.by_name.get(name)
    if service is None:
        raise _error(f"event {event!r}: handler service {name!r} is not registered",
                     "ENOTFOUND")
    if (service.offer.md_name, service.offer.layout_hash) != (md_name, layout_hash):
        raise _error(f"event {event!r}: handler service {name!r} is registered with md "
                     f"{service.offer.md_name!r}, not {md_name!r}", "ELAYOUT")
    others = [(s, c) for s, c in _live(control, connections) if c.event == event
              and s is not service]
    for _, other in others[:1]:
        if other.layout_hash != layout_hash:
            raise _error(f"event {event!r}: layout of md {md_name!r} (hash 0x{layout_hash:016x})"
                         f" differs from its handlers' md {other.md_name!r} (hash "
                         f"0x{other.layout_hash:016x})", "ELAYOUT")
    if len(others) >= MAX_HANDLERS:
        raise _error(f"event {event!r} has {len(others)} handlers already, its limit is "
                     f"{MAX_HANDLERS}", "ELIMIT")
    connections[service] = Connection(event, md_name, layout_hash, signature, connect.lower())
    return {"event": event, "handlers": len(others) + 1}


async def events(control: Control, command: dict[str, Any]) -> dict[str, Any]:
    connections = _connections(control)
    only = command["name"]
    listing: dict[str, dict[str, Any]] = {}
    for service, conn in _live(control, connections):
        if only is not None and conn.event != only:
            continue
        entry = listing.setdefault(conn.event, {
            "name": conn.event, "md_name": conn.md_name,
            "layout_hash": f"0x{conn.layout_hash:016x}", "signature": conn.signature,
            "handlers": []})
        client = service.provider
        entry["handlers"].append({
            "service": service.name, "client": client.name, "client_id": client.id,
            "host_id": service.offer.host_id, "group": service.offer.group,
            "connect": conn.connect, "calls": service.calls, "errors": service.errors})
    return {"events": [listing[name] for name in sorted(listing)]}


def _string(name: str, help_text: str, check: Any = None) -> Arg:
    return Arg(name, "str", help_text, required=True, check=check)


register(
    Command("event_connect", "a handler's libln, right after registering the handler's "
            "service ln_event/EVENT/CLIENT.N: its connect struct", "events", event_connect,
            (_string("event", "the event's name", _event_name),
             _string("service", "the handler's service (ln_event/EVENT/CLIENT.N)"),
             _string("md_name", "the event's md"),
             _string("layout_hash", "the md's layout hash (hex)", _hex),
             _string("signature", "the md's signature"),
             _string("connect", "the connect struct, wire form in hex")),
            result="event, handlers (how many are connected now)", changes_state=True,
            code="EINVAL", console=False, cli=False, script=""),
    Command("events", "every event with connected handlers (or one)", "events", events,
            (Arg("name", "str", "only this event", nullable=True, positional=True,
                 check=_event_name),),
            result="events: [{name, md_name, layout_hash, signature, handlers: [{service, "
                   "client, client_id, host_id, group, connect, calls, errors}]}]",
            code="EINVAL", script_result=lambda result: result["events"]),
)
