"""One links_and_nodes topic as a Foxglove channel: JSON messages with the md's JSON Schema,
read from the topic only while at least one Foxglove client subscribes.

Each subscribed channel has a reader thread with its own libln client (the introspection
reader: latest mode by default, queued with the rule's `queued=N`), which decodes every sample
it reads with the md (introspect.decode: numbers, char fields as strings, nested objects),
drops samples over the rule's rate, and logs the JSON with the sample's publish time.
"""

from __future__ import annotations

import json
import threading
import time
from dataclasses import dataclass
from typing import Any

from ln_generate import MessageDef

from ..md_json import SCHEMA_ENCODING, encode, root_schema
from ..tools.introspection import values as fmt
from ..tools.introspection.client import TopicReader
from ..tools.introspection.commands import CommandError, Context, follow, topic_layout
from ..zenoh_bridge.config import TopicRule

RETRY = 1.0  # seconds before a reader that failed subscribes again


@dataclass
class ChannelStats:
    read: int = 0
    sent: int = 0
    rate_limited: int = 0
    errors: int = 0
    subscriptions: int = 0  # times a reader was started


class TopicChannel:
    """`info` is the manager's topic_info answer, `md` its checked md (topic_layout)."""

    def __init__(self, bridge: Any, info: dict[str, Any], md: MessageDef, rule: TopicRule
                 ) -> None:
        import foxglove

        self.bridge = bridge
        self.name = str(info["name"])
        self.md = md
        self.md_name = md.name
        self.layout_hash = md.layout_hash
        self.rule = rule
        self.stats = ChannelStats()
        self.clients: set[int] = set()
        self.stale = False  # the topic has another layout now: the next poll advertises anew
        self._stop: threading.Event | None = None
        schema = json.dumps(root_schema(md.struct, md.doc)).encode()
        self.channel = foxglove.Channel(
            self.name, schema=foxglove.Schema(name=md.name, encoding=SCHEMA_ENCODING,
                                              data=schema),
            message_encoding="json", context=bridge.context,
            metadata={"md_name": md.name, "layout_hash": f"0x{md.layout_hash:016x}",
                      "message_size": str(md.struct.size),
                      "mode": f"queued {rule.buffers}" if rule.queued else "latest",
                      **({"rate": f"{rule.rate:g}"} if rule.rate else {})})
        self.id = self.channel.id()

    # ---- subscriptions (called with the bridge's lock held: no sdk calls here) ---------------
    def subscribe(self, client_id: int) -> None:
        first = not self.clients
        self.clients.add(client_id)
        if first:
            self._start()

    def unsubscribe(self, client_id: int) -> None:
        self.clients.discard(client_id)
        if not self.clients and self._stop is not None:
            self._stop.set()  # the reader ends within a read slice
            self._stop = None
            self.bridge.say(f"topic '{self.name}': no Foxglove subscriber left: unsubscribed",
                            verbose=True)

    def _start(self) -> None:
        self._stop = threading.Event()
        self.stats.subscriptions += 1
        threading.Thread(target=self._run, args=(self._stop,), daemon=True,
                         name=f"foxglove {self.name}").start()

    # ---- the reader ------------------------------------------------------------------------
    def _run(self, stop: threading.Event) -> None:
        ctx = Context(self.bridge.link.control, self.bridge.address, self.bridge.say, stop,
                      self.bridge.config.name)
        last_error = ""
        while not stop.is_set():
            try:
                self._follow(ctx)
            except CommandError as exc:
                self.stats.errors += 1
                if str(exc) != last_error:  # once per reason, not every retry
                    last_error = str(exc)
                    self.bridge.warn(f"topic '{self.name}': {exc} (trying again every "
                                     f"{RETRY:g} s while subscribed)")
                stop.wait(RETRY)

    def _follow(self, ctx: Context) -> None:
        from ..errors import LnError

        info = ctx.control("topic_info", name=self.name)
        md = topic_layout(info)  # the topic may be another one of the same name by now
        if md.layout_hash != self.layout_hash:
            self.stale = True
            raise CommandError(f"its layout changed to 0x{md.layout_hash:016x} (the channel "
                               "is advertised again with the new schema)")
        try:
            reader = TopicReader(ctx.address, f"{ctx.client_prefix}_topic", self.name,
                                 info["md_name"], int(info["layout_hash"], 16),
                                 int(info["message_size"]), self.rule.depth)
        except LnError as exc:
            raise CommandError(f"cannot subscribe: {exc}") from None
        self.bridge.say(f"topic '{self.name}': a Foxglove client subscribed: reading it "
                        f"({'queued, ' + str(self.rule.buffers) if self.rule.queued else 'latest'}"
                        " mode)", verbose=True)
        stats, layout, log = self.stats, md.struct, self.channel.log
        interval = 1.0 / self.rule.rate if self.rule.rate else 0.0
        next_ok = 0.0
        with reader:
            for sample in follow(ctx, reader, self.name):
                stats.read += 1
                if interval:
                    now = time.monotonic()
                    if now < next_ok:
                        stats.rate_limited += 1
                        continue
                    # an even pace while on time; after a pause, from now
                    next_ok = next_ok + interval if now < next_ok + interval \
                        else now + interval
                try:
                    payload = encode(fmt.decode(layout, sample.data))
                except fmt.IntrospectError as exc:
                    raise CommandError(str(exc)) from None
                log(payload, log_time=sample.timestamp_ns)
                stats.sent += 1

    def close(self) -> None:
        """Stop reading and unadvertise the channel (not with the bridge's lock held)."""
        if self._stop is not None:
            self._stop.set()
            self._stop = None
        self.channel.close()
