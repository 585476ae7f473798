"""The manager's web UI (docs/webui.md): `ln_manager --webui` (on the manager's port),
`--webui-port N`, or `webui: on` / `webui_port: N` in the instance section; HTTPS with
`--webui-tls-cert/-key` or `webui_tls_cert/key`.  plan() turns those options into a Plan or
a WebUIError saying what is wrong (a non-loopback address needs TLS or --webui-insecure).
The server is imported on first use of WebUI (module __getattr__), so that `ln_manager
--help` and a manager without a web UI do not load it."""

from __future__ import annotations

import argparse
import os
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
    tls_cert: str | None = None  # both or neither: HTTPS on the web UI's own port
    tls_key: str | None = None
    warning: str | None = None  # to print at start (--webui-insecure off loopback)

    @property
    def scheme(self) -> str:
        return "https" if self.tls_cert else "http"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--webui", action="store_true",
                        help="serve the web UI on the manager's port (docs/webui.md)")
    parser.add_argument("--webui-port", type=int, default=None, metavar="N",
                        help="serve the web UI on its own port N (0: a free one)")
    parser.add_argument("--webui-host", default=None, metavar="ADDRESS",
                        help="address of --webui-port (default 127.0.0.1; another one needs "
                             "an auth file and TLS)")
    parser.add_argument("--webui-tls-cert", default=None, metavar="FILE",
                        help="PEM certificate (chain): the web UI speaks HTTPS on "
                             "--webui-port (overrides webui_tls_cert)")
    parser.add_argument("--webui-tls-key", default=None, metavar="FILE",
                        help="PEM private key of --webui-tls-cert, mode 600 (overrides "
                             "webui_tls_key)")
    parser.add_argument("--webui-insecure", action="store_true",
                        help="serve the web UI over plain HTTP on a non-loopback address "
                             "(passwords and cookies cross the network in the clear)")


def plan(args: argparse.Namespace, config: Any) -> Plan | None:
    """What to run, from the command line and the instance section; None: no web UI."""
    inst = getattr(config, "instance", None)
    port = args.webui_port if args.webui_port is not None else getattr(inst, "webui_port",
                                                                        None)
    if not (args.webui or port is not None or getattr(inst, "webui", False)):
        given = [o for o, v in (("--webui-tls-cert", args.webui_tls_cert),
                                ("--webui-tls-key", args.webui_tls_key),
                                ("--webui-insecure", args.webui_insecure)) if v]
        if given:
            raise WebUIError(f"{given[0]} without a web UI: add --webui-port N (or --webui)")
        return None
    from .auth import auth_file_from

    if port is not None and not 0 <= port <= 65535:
        raise WebUIError(f"web UI port {port} is not a TCP port")
    auth_file = auth_file_from(getattr(inst, "webui_auth_file", None))
    if port is None:
        host = args.host
    else:
        host = args.webui_host or ("127.0.0.1" if auth_file is None else args.host)
    where = "the manager's address" if port is None else "--webui-host"
    if auth_file is None and not is_loopback(host):
        raise WebUIError(f"web UI without an auth file listens on loopback only, but "
                         f"{where} is {host}: set webui_auth_file in the instance section or "
                         "LNM_WEBUI_AUTH_FILE (docs/webui.md), or serve it on a loopback "
                         "--webui-port")
    cert, key = _tls_files(args, inst)
    if cert and port is None:
        raise WebUIError("the web UI over TLS needs a port of its own (the manager's port "
                         "speaks the plain client protocol): add --webui-port N or webui_port "
                         "in the instance section")
    warning = None
    if not cert and not is_loopback(host):
        if not args.webui_insecure:
            raise WebUIError(f"web UI on {host} ({where}) without TLS refused: its password "
                             "and session cookie would cross the network in the clear; give "
                             "--webui-tls-cert FILE --webui-tls-key FILE (or webui_tls_cert/"
                             "webui_tls_key in the instance section; docs/webui.md, \"TLS\"), "
                             "listen on loopback, or accept the risk with --webui-insecure")
        warning = (f"web UI on {host} over plain HTTP (--webui-insecure): passwords and "
                   "session cookies cross the network in the clear")
    return Plan(port, host, auth_file, cert, key, warning)


def _tls_files(args: argparse.Namespace, inst: Any) -> tuple[str | None, str | None]:
    """The certificate and key (the command line's over the section's, each on its own);
    WebUIError if only one of the two is given."""
    cert = args.webui_tls_cert or getattr(inst, "webui_tls_cert", None)
    key = args.webui_tls_key or getattr(inst, "webui_tls_key", None)
    if bool(cert) != bool(key):
        missing = "key (--webui-tls-key, webui_tls_key)" if cert else \
            "certificate (--webui-tls-cert, webui_tls_cert)"
        raise WebUIError(f"web UI TLS needs a certificate and its key, but the {missing} "
                         "is missing")
    return (os.path.abspath(cert) if cert else None), (os.path.abspath(key) if key else None)
