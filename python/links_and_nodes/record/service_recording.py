"""ln_record --services: the calls of a ServiceCallTap written beside the topics, one channel
per service (docs/recording.md, "Service calls"), into the recorder's SplitWriter under its
lock, so they land in the same rotating files."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from .service_calls import ServiceCall, ServiceCallTap, channel_fields, encode_call

DRAIN = 0.2  # seconds: on stop, calls still on their way are taken until none came for this


class ServiceChannel:
    """A service's channel for SplitWriter.add_channel (re-added in every file)."""

    def __init__(self, call: ServiceCall) -> None:
        self.fields = channel_fields(call.service, call.md_name, call.layout_hash,
                                     call.signature)

    def add_to(self, writer: Any, topic: str) -> int:
        return int(writer.add_channel(topic, **self.fields))


class ServiceRecording:
    """Records the calls of the services matching `patterns` through `recorder` (a Recorder:
    its `out`, `lock`, and `_fail` for a write error) until stop()."""

    def __init__(self, recorder: Any, manager: str, patterns: list[str],
                 say: Callable[[str], None] = lambda text: None) -> None:
        self.recorder = recorder
        self.say = say
        self.channels: dict[tuple[str, int], int] = {}  # (service, layout hash) -> channel
        self.counts: dict[str, int] = {}
        self.calls = 0
        self.tap = ServiceCallTap(manager, patterns, "ln_record", on_attach=self._attached)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True,
                                        name="ln_record services")
        self._thread.start()

    @property
    def drops(self) -> int:
        return self.tap.drops

    def _attached(self, service: str, provider: str) -> None:
        self.say(f"recording the calls of service '{service}' (provider '{provider}')")

    def _channel(self, call: ServiceCall) -> int:
        key = (call.service, call.layout_hash)
        channel = self.channels.get(key)
        if channel is None:
            channel = self.recorder.out.add_channel(call.service, ServiceChannel(call))
            self.channels[key] = channel
        return channel

    def _run(self) -> None:
        rec = self.recorder
        while not (self._stop.is_set() and self.tap.calls.empty()):
            call = self.tap.get(0.1)
            if call is None:
                continue
            data = encode_call(call)
            try:
                with rec.lock:
                    if rec.error is not None:
                        return
                    channel = self._channel(call)
                    n = self.counts.get(call.service, 0)
                    rec.out.write(channel, n, call.request_time_ns, data)
                    self.counts[call.service] = n + 1
                    self.calls += 1
            except OSError as exc:
                rec._fail(f"cannot write {rec.out.writer.path}: {exc}")
                return

    def stop(self) -> None:
        """Stop tapping, then write what was received."""
        self.tap.close(drain=DRAIN)
        self._stop.set()
        self._thread.join()
