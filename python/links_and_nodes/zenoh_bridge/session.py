"""Importing zenoh (an optional dependency) and opening ln_zenoh's session from its settings.

The settings go into a Zenoh config: the file given with --zenoh-config (JSON5: TLS, access
control, ... docs/zenoh.md "Security") or Zenoh's defaults, then mode, listen and connect
endpoints, no multicast scouting (endpoints are explicit) and a connect retry that keeps
trying while the other side is away.  With the native core (native.py) that configuration is
the core's session, and the Python session is a client of it."""

from __future__ import annotations

import json
from typing import Any

from .config import BridgeConfig

INSTALL_HINT = "pip install eclipse-zenoh"


class ZenohMissing(ImportError):
    """The zenoh package is not installed."""


def import_zenoh() -> Any:
    try:
        import zenoh
    except ImportError as exc:
        raise ZenohMissing(f"the Python package zenoh is not installed ({INSTALL_HINT}): "
                           f"{exc}") from None
    return zenoh


def zenoh_config(config: BridgeConfig) -> Any:
    zenoh = import_zenoh()
    zc = zenoh.Config.from_file(config.zenoh_config) if config.zenoh_config else zenoh.Config()
    zc.insert_json5("mode", json.dumps(config.mode))
    if config.listen or not config.zenoh_config:
        zc.insert_json5("listen/endpoints", json.dumps(config.listen))
    if config.connect:
        zc.insert_json5("connect/endpoints", json.dumps(config.connect))
    if not config.zenoh_config:
        zc.insert_json5("scouting/multicast/enabled", "false")
        zc.insert_json5("connect/exit_on_failure", "false")
        zc.insert_json5("connect/timeout_ms", "2000")
        zc.insert_json5("connect/retry", json.dumps(
            {"period_init_ms": 250, "period_max_ms": 2000, "period_increase_factor": 2}))
    return zc


def open_session(config: BridgeConfig, say: Any, stop: Any,
                 native: bool) -> tuple[Any, Any] | None:
    """The Python session and, if `native`, the core (native.Core) it is a client of; in
    client mode it retries (every second, saying why) until a router answers or `stop` (an
    Event) is set, then returns None."""
    from .native import Core, CoreError

    zenoh = import_zenoh()
    zenoh.try_init_log_from_env()  # RUST_LOG=zenoh=info (or debug) shows Zenoh's own log
    while True:
        core = None
        try:
            zc = zenoh_config(config)
            if native:
                core = Core(zc, config.mode, say)
                zc = core.client_config(zenoh_config(config))
            return zenoh.open(zc), core
        except (zenoh.ZError, CoreError) as exc:
            if core is not None:
                core.close()
            if config.mode != "client":
                raise
            say(f"cannot open the Zenoh session (will retry): {exc}")
        if stop.wait(1.0):
            return None
