"""How links_and_nodes names things on a host: the sanitized instance, shared-memory segment
names, the runtime directory and service socket names, and which topic, service, md and
client names are valid.  The one Python home of these rules;
libln's naming.c is the C one, and tests/python/naming checks that both give the same
names."""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from pathlib import Path

_UNSAFE = re.compile(r"[^A-Za-z0-9_-]")
MAX_NAME = 255  # bytes of a topic, service, md or client name
_TOPIC_RE = re.compile(r"[A-Za-z0-9_.:/-]+\Z")
_MD_COMPONENT_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
# A provider's Unix socket in the runtime directory, as service_socket() names it.
SERVICE_SOCKET_NAME = re.compile(r"svc\.[0-9]+\.[0-9]+\.sock\Z")


def sanitize_instance(instance: str) -> str:
    """The instance as it appears in names: each character but A-Z a-z 0-9 _ - becomes one
    '_', so no '.' or '/' can make one instance's names match another's.  Sanitizing a
    sanitized name changes nothing."""
    return _UNSAFE.sub("_", instance)


def segment_prefix(instance: str) -> str:
    """`/ln.<sanitized instance>.`: every segment of the instance starts so."""
    return f"/ln.{sanitize_instance(instance)}."


def segment_name(instance: str, topic_id: int, generation: int, tag: str = "") -> str:
    """`/ln.<sanitized instance>.<topic id>.<generation>`, with `.<tag>` after it when a tag
    is given (segments a daemon makes for another host's topic)."""
    name = f"{segment_prefix(instance)}{topic_id}.{generation}"
    return f"{name}.{tag}" if tag else name


def runtime_dir(instance: str, env: Mapping[str, str] | None = None) -> Path:
    """The instance's runtime directory: $LN_RUNTIME_DIR (the directory itself), else
    $XDG_RUNTIME_DIR/ln/<sanitized instance>, else /tmp/ln-<uid>/<sanitized instance>."""
    env = os.environ if env is None else env
    if env.get("LN_RUNTIME_DIR"):
        return Path(env["LN_RUNTIME_DIR"])
    if env.get("XDG_RUNTIME_DIR"):
        return Path(env["XDG_RUNTIME_DIR"]) / "ln" / sanitize_instance(instance)
    return Path(f"/tmp/ln-{os.getuid()}") / sanitize_instance(instance)


def service_socket(directory: Path | str, pid: int, n: int) -> Path:
    """`<directory>/svc.<pid>.<n>.sock`, a service provider's Unix socket."""
    return Path(directory) / f"svc.{pid}.{n}.sock"


def parse_segment_name(instance: str, name: str) -> tuple[int, int] | None:
    """(topic id, generation) of a segment_name() of `instance` without a tag, with or without
    its leading '/' (as /dev/shm lists it); None if `name` is not one."""
    prefix = segment_prefix(instance)
    match = re.fullmatch(rf"/?{re.escape(prefix[1:])}([0-9]{{1,9}})\.([0-9]{{1,9}})", name)
    return (int(match[1]), int(match[2])) if match else None


# ---- names clients give: topics, services, events, mds, clients ------------------------


def topic_name_problem(name: str, what: str = "topic") -> str | None:
    """Why `name` is not a valid topic name, or None; `what` names the kind of name in the
    text (services follow the same rules)."""
    size = len(name.encode("utf-8"))
    if not 1 <= size <= MAX_NAME:
        return f"{what} name of {size} bytes, must be 1..{MAX_NAME}"
    if not _TOPIC_RE.match(name):
        return f"{what} name {name!r} may only contain A-Z a-z 0-9 _ . : / -"
    if name.startswith("."):
        return f"{what} name {name!r} must not start with '.'"
    return None


def md_name_problem(name: str) -> str | None:
    """Why `name` is not a valid md name ('/'-separated identifiers), or None."""
    size = len(name.encode("utf-8"))
    if not 1 <= size <= MAX_NAME:
        return f"md name of {size} bytes, must be 1..{MAX_NAME}"
    for part in name.split("/"):
        if not _MD_COMPONENT_RE.match(part):
            return (f"md name {name!r}: component {part!r} is not an identifier "
                    "(letters, digits, '_', not starting with a digit)")
    return None


def client_name_problem(name: str) -> str | None:
    """Why `name` cannot be a client name (it shows up in logs and tools), or None."""
    size = len(name.encode("utf-8"))
    if not 1 <= size <= MAX_NAME:
        return f"client name of {size} bytes, must be 1..{MAX_NAME}"
    if not name.isprintable():
        return f"client name {name!r} contains control characters"
    return None
