"""Live introspection in the scripting API (docs/introspection.md): the methods of
`links_and_nodes.manager.connect(...)` that look at topics, mds and services and return
Python values.  topic_echo/hz/bw and service_call attach a libln client to the manager
(loaded on first use); md_show only asks the manager (topic_info, a command of the table,
is made by commands/script_methods.py)."""

from __future__ import annotations

from typing import Any

from .args import DEFAULT_TIMEOUT
from .stats import DEFAULT_WINDOW, PeriodStats


class Introspection:
    """Mixed into scripting.Manager, whose command() and address it uses."""

    address: str

    def command(self, op: str, *, wait: float | None = None, **args: Any) -> dict[str, Any]:
        raise NotImplementedError

    def _context(self) -> Any:
        from .commands import CommandError, Context
        from ..frontends.scripting import ManagerError

        def control(op: str, **fields: Any) -> dict[str, Any]:
            try:
                return self.command(op, **fields)
            except ManagerError as exc:
                raise CommandError(str(exc)) from None

        return Context(control, self.address, lambda _text: None, client_prefix="ln_script")

    def _run(self, func: Any, *args: Any, **kwargs: Any) -> Any:
        from .commands import CommandError
        from ..frontends.scripting import ManagerError

        try:
            return func(self._context(), *args, **kwargs)
        except CommandError as exc:
            raise ManagerError(str(exc)) from None

    def md_show(self, name: str, recursive: bool = False) -> str:
        """The text of md `name` from the manager's md search path; with `recursive` also
        of every md it uses, each under a `# ==== NAME: PATH` line."""
        from .commands import md_text

        return self._run(md_text, name, recursive)

    def topic_echo(self, name: str, n: int = 1, field: str | None = None,
                   timeout: float | None = DEFAULT_TIMEOUT) -> list[dict[str, Any]]:
        """The next `n` samples of topic `name` (fewer if `timeout` seconds pass first), each
        {"seq", "publish_time" (s), "publish_time_ns", "data"} with data the decoded sample,
        or only the value at `field` (e.g. "target.position[2]"; then also "field")."""
        from .commands import echo_records

        return self._run(echo_records, name, n, timeout, field)

    def topic_hz(self, name: str, duration: float | None = 2.0, n: int | None = None,
                 window: int = DEFAULT_WINDOW) -> dict[str, Any]:
        """Rate statistics of topic `name` over `duration` seconds or `n` samples (whichever
        ends first): samples, periods, missed, span_s, rate_hz, mean_s, min_s, max_s, std_s
        (introspect_stats.PeriodStats; fewer than two samples: rate_hz 0, the rest None)."""
        return self._measure(name, duration, n, window, "hz")[0]

    def topic_bw(self, name: str, duration: float | None = 2.0, n: int | None = None,
                 window: int = DEFAULT_WINDOW) -> dict[str, Any]:
        """topic_hz's statistics plus message_size and bytes_per_s (size x rate)."""
        stats, size = self._measure(name, duration, n, window, "bw")
        return {**stats, "message_size": size, "bytes_per_s": stats["rate_hz"] * size}

    def _measure(self, name: str, duration: float | None, n: int | None, window: int,
                 purpose: str) -> tuple[dict[str, Any], int]:
        from .commands import measure, topic_info

        if duration is None and n is None:
            raise ValueError("give a duration or a number of samples n")

        def run(ctx: Any) -> tuple[dict[str, Any], int]:
            info = topic_info(ctx, name)
            stats = measure(ctx, info, n, duration, window, purpose=purpose)
            if stats is None:
                stats = PeriodStats(0, 0, 0, 0.0, 0.0, None, None, None, None)
            return stats.as_dict(), int(info["message_size"])

        return self._run(run)

    def service_call(self, name: str, request: dict[str, Any] | str | None = None,
                     timeout: float = DEFAULT_TIMEOUT) -> dict[str, Any]:
        """Call service `name` once: `request` as a dict of request fields (nested dicts,
        lists) or request text ('a: 1, b: [1, 2]' or JSON); the response as a dict.  An
        error response raises ManagerError with the provider's text."""
        from .commands import service_call_values

        return self._run(service_call_values, name, request or {}, timeout)
