"""The manager's web UI (docs/webui.md): `ln_manager --webui` (on the manager's port),
`--webui-port N`, or `webui: on` / `webui_port: N` in the instance section.  setup() turns
those options into a running WebUI or a WebUIError saying what is wrong.  The server is
imported on first use of WebUI (module __getattr__), so that `ln_manager --help` and a
manager without a web UI do not load it."""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from typing import Any

from ....addresses import is_loopback

__all__ = ["REQUEST_LINE_STARTS", "Plan", "WebUI", "WebUIError", "add_arguments", "plan"]


def __getattr__(name: str) -> Any:
    if name in ("REQUEST_LINE_STARTS", "WebUI"):
        from . import server

        return getattr(server, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


class WebUIError(Exception):
    """The web UI cannot run as asked; the text says why."""


@dataclass
class Plan:
    port: int | None  # None: the manager's own port
    host: str
    auth_file: str | None


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--webui", action="store_true",
                        help="serve the web UI on the manager's port (docs/webui.md)")
    parser.add_argument("--webui-port", type=int, default=None, metavar="N",
                        help="serve the web UI on its own port N (0: a free one)")
    parser.add_argument("--webui-host", default=None, metavar="ADDRESS",
                        help="address of --webui-port (default 127.0.0.1; another one needs "
                             "an auth file)")


def plan(args: argparse.Namespace, config: Any) -> Plan | None:
    """What to run, from the command line and the instance section; None: no web UI."""
    inst = getattr(config, "instance", None)
    port = args.webui_port if args.webui_port is not None else getattr(inst, "webui_port",
                                                                        None)
    if not (args.webui or port is not None or getattr(inst, "webui", False)):
        return None
    from .auth import auth_file_from

    if port is not None and not 0 <= port <= 65535:
        raise WebUIError(f"web UI port {port} is not a TCP port")
    auth_file = auth_file_from(getattr(inst, "webui_auth_file", None))
    if port is None:
        host = args.host
    else:
        host = args.webui_host or ("127.0.0.1" if auth_file is None else args.host)
    if auth_file is None and not is_loopback(host):
        where = "the manager's address" if port is None else "--webui-host"
        raise WebUIError(f"web UI without an auth file listens on loopback only, but "
                         f"{where} is {host}: set webui_auth_file in the instance section or "
                         "LNM_WEBUI_AUTH_FILE (docs/webui.md), or serve it on a loopback "
                         "--webui-port")
    return Plan(port, host, auth_file)
