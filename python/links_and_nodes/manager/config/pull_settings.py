"""The pull settings of a `topics` line (`pull:ndn-udp, pull_port:N, pull_prefix:/URI, ...`,
docs/pull.md) and the NDN names of pull topics: a topic `arm.state` under the prefix
`/ln/robot` is `/ln/robot/arm.state` (split on '/', '.' stays inside a component)."""

from __future__ import annotations

import ipaddress
import re

from ... import transports
from .model import PullSetting
from .text import Value
from .values import fail, parse_int

PULL_TRANSPORTS = transports.PULL
PULL_KEYS = ("pull", "pull_port", "pull_prefix", "pull_history", "pull_freshness_ms",
             "pull_key", "pull_address")
MAX_HISTORY = 65536
MAX_FRESHNESS_MS = (1 << 32) - 1
_UNRESERVED = re.compile(r"[A-Za-z0-9._~\-]")
_PREFIX_COMPONENT = re.compile(r"(?:[A-Za-z0-9._~\-]|%[0-9A-Fa-f]{2})+\Z")
_HEX = re.compile(r"(?:[0-9A-Fa-f]{2})+\Z")


def parse_pull(found: dict[str, Value], pattern: str) -> PullSetting | None:
    """The PullSetting of one line's `pull*` items (name -> value), None if it has none;
    LineError at the first bad value."""
    if not found:
        return None
    if "pull" not in found:
        name, v = next(iter(found.items()))
        raise fail(v, f"'{name}' needs 'pull:{transports.NDN_UDP}' on the same line (topic pattern "
                      f"'{pattern}')")
    word = found["pull"].text.strip().lower()
    if word not in PULL_TRANSPORTS:
        raise fail(found["pull"], f"unknown pull transport '{found['pull'].text}' "
                                  f"(known: {', '.join(PULL_TRANSPORTS)})")
    out = PullSetting(word)
    if word == transports.PULL_OFF:
        extra = next((n for n in found if n != "pull"), None)
        if extra is not None:
            raise fail(found[extra], f"'{extra}' has no effect with 'pull:off'")
        return out
    values: dict[str, object] = {}
    for name, v in found.items():
        if name == "pull_port":
            values["port"] = parse_int(v, name, 1, 65535)
        elif name == "pull_history":
            values["history"] = parse_int(v, name, 1, MAX_HISTORY)
        elif name == "pull_freshness_ms":
            values["freshness_ms"] = parse_int(v, name, 0, MAX_FRESHNESS_MS)
        elif name == "pull_prefix":
            values["prefix"] = parse_prefix(v)
        elif name == "pull_key":
            if not _HEX.match(v.text):
                raise fail(v, "'pull_key' must be the HMAC key as an even number of hex "
                              f"digits, got '{v.text}'")
            values["key"] = bytes.fromhex(v.text)
        elif name == "pull_address":
            try:
                values["address"] = str(ipaddress.ip_address(v.text))
            except ValueError:
                raise fail(v, "'pull_address' must be an IPv4 or IPv6 address to bind, "
                              f"got '{v.text}'") from None
    return PullSetting(word, **values)  # type: ignore[arg-type]


def parse_prefix(v: Value) -> str:
    """An NDN name prefix: '/', then components of unreserved characters or %XX escapes
    ('/' alone is the root); returned without a trailing '/'."""
    text = v.text
    if not text.startswith("/"):
        raise fail(v, f"'pull_prefix' must be an NDN name starting with '/', got '{text}'")
    body = text[1:].rstrip("/")
    for part in body.split("/") if body else []:
        if not _PREFIX_COMPONENT.match(part):
            raise fail(v, f"'pull_prefix' component '{part}' of '{text}' may only hold "
                          "A-Z a-z 0-9 . _ ~ - and %XX escapes")
    return "/" + body


def uri_component(text: str) -> str:
    """One generic NDN name component as a URI part (RFC 3986 unreserved characters stay,
    every other byte is %XX; a component of periods only gets three more)."""
    out = "".join(c if _UNRESERVED.match(c) else "".join(f"%{b:02X}" for b in c.encode())
                  for c in text)
    return out + "..." if set(out) <= {"."} else out


def default_prefix(instance: str) -> str:
    return "/ln/" + uri_component(instance)


def pull_uri(setting: PullSetting, instance: str, topic: str) -> str:
    """The NDN name (URI) under which `topic` is served."""
    prefix = setting.prefix if setting.prefix is not None else default_prefix(instance)
    return prefix.rstrip("/") + "/" + "/".join(uri_component(c) for c in topic.split("/"))

