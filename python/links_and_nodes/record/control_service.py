"""The control service of a running ln_play (md ln/player): pause, resume, step, seek,
set_rate and status for scripts and the web UI, answered on the player's own thread."""

from __future__ import annotations

from typing import Any

from .playback import CommandError, Playback, Status

CONTROL_MD = "ln/player"
CONTROL_GROUP = "ln_play.control"  # handled only inside Controller.wait
LN_EINVAL = -1  # ln.h's LN_EINVAL, the status of a refused command


def default_name(client_name: str) -> str:
    """The service name when --control-service does not give one."""
    return f"{client_name}.control"


def _fields(st: Status) -> dict[str, Any]:
    return {"state": st.state, "position_ns": st.position_ns, "rate": st.rate,
            "played": st.played, "first_ns": st.first_ns, "last_ns": st.last_ns}


def provide(client: Any, name: str, playback: Playback) -> Any:
    """Register the service `name`; its requests are handled by
    client.wait_and_handle_service_group_requests(CONTROL_GROUP, ...)."""

    def handle(request: Any) -> None:
        req = request.req
        try:
            st = playback.command(str(req.command), int(req.time_ns), bool(req.relative),
                                  float(req.rate))
        except CommandError as exc:
            request.respond({"status": LN_EINVAL, "error": str(exc),
                             **_fields(playback.status())})
            return
        request.respond({"status": 0, "error": "", **_fields(st)})

    return client.get_service_provider(name, CONTROL_MD, handle, group=CONTROL_GROUP)
