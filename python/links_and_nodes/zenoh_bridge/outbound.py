"""Outbound topics (links_and_nodes -> Zenoh): one subscription and one thread per topic.

The thread reads every sample the subscription gives (latest mode: the newest; queued: each
one) and puts it on `P/topic/<name>` with the attachment (wire.py), but only while a remote
subscriber matches (Zenoh's matching listener): samples read while none does are counted as
`unmatched`, samples over the topic's rate limit as `rate_limited`.  With --ros2 each sample
also goes, as CDR, under the topic's ROS 2 key while a subscriber matches that one.

With the native core (native.py) and without ROS 2, the core declares the publisher and reads
the subscription in its own thread, with the same rules and counters; this object keeps the
liveliness token and the log lines.  With batches on (bridge.batching) the core also puts the
samples in batches on `P/batch/<name>` while a bridge takes them there (docs/zenoh.md
"Batches between bridges"); "a remote subscriber matches" then means either key.
"""

from __future__ import annotations

import ctypes
import threading
import time
from typing import Any

from ..md_loader import message_class
from .config import TopicRule
from .ros2 import Ros2Out
from .wire import AttachmentEncoder, batch_key, live_key, topic_key

READ_SLICE = 0.2  # seconds a reader waits before it looks at the stop flag


class OutTopic:
    def __init__(self, bridge: Any, name: str, md_name: str, rule: TopicRule) -> None:
        import zenoh

        self.bridge = bridge
        self.name = name
        self.md_name = md_name
        self.rule = rule
        self.stats = bridge.stats.topic(name, "out")
        self.stats.md_name = md_name
        cls = message_class(md_name)
        if cls._ln_has_dynamic_:
            raise ValueError(f"md '{md_name}' has dynamic fields: a sample holds their "
                             "pointers, not their data")
        self.layout_hash = cls.LAYOUT_HASH
        self._attachment = AttachmentEncoder(md_name, cls.LAYOUT_HASH)
        bridge.md_server.serve(md_name)
        self._stop = threading.Event()
        self._closers: list[Any] = []
        self.port: Any = None
        self.native: Any = None  # native.OutTopic: the core reads and puts
        self.ros2: Ros2Out | None = None
        self._thread: threading.Thread | None = None
        self.key = topic_key(bridge.prefix, name)
        if bridge.core is not None and not bridge.config.ros2:
            self._open_native()
            return
        try:
            congestion = (zenoh.CongestionControl.BLOCK if rule.queued
                          else zenoh.CongestionControl.DROP)
            self.publisher = bridge.session.declare_publisher(
                self.key, congestion_control=congestion,
                reliability=zenoh.Reliability.RELIABLE, express=not rule.queued)
            self._closers.append(self.publisher)
            self.matching = self.publisher.matching_status.matching
            self._closers.append(self.publisher.declare_matching_listener(
                lambda status: self._on_matching(status.matching)))
            self.matching = self.publisher.matching_status.matching  # a change before the above
            self._closers.append(bridge.session.liveliness().declare_token(
                live_key(bridge.prefix, "topic", name)))
            if bridge.config.ros2:
                self.ros2 = Ros2Out(bridge.session, bridge.config.ros2_domain, bridge.ros2_node,
                                    name, md_name, cls.LAYOUT_HASH, rule.depth,
                                    self._on_ros2_matching)
                self._closers.append(self.ros2)
            # Subscribed last: a publisher that waits for this subscriber finds the Zenoh
            # side ready, its matching status known.
            self.port = bridge.client.subscribe(name, md_name, buffers=rule.depth)
        except BaseException:
            self.close()
            raise
        self._set_state()
        self._thread = threading.Thread(target=self._run, daemon=True, name=f"out {name}")
        self._thread.start()

    def _open_native(self) -> None:
        from .native import Counters

        bridge, rule = self.bridge, self.rule
        try:
            self._closers.append(bridge.session.liveliness().declare_token(
                live_key(bridge.prefix, "topic", self.name)))
            self.port = bridge.client.subscribe(self.name, self.md_name, buffers=rule.depth)
            counters = Counters()
            self.native = bridge.core.out_topic(
                key=self.key, batch_key=batch_key(bridge.prefix, self.name) if bridge.batching
                else None, port=self.port, md_name=self.md_name, layout_hash=self.layout_hash,
                queued=rule.queued, rate=rule.rate, counters=counters,
                label=f"topic '{self.name}'", on_match=self._on_matching)
            bridge.stats.add_native(self.name, "out", counters)
        except BaseException:
            self.close()
            raise
        self.matching = self.native.matching
        self._set_state()

    def _set_state(self) -> None:
        remote = self.matching or (self.ros2 is not None and self.ros2.matching)
        self.stats.state = "sending" if remote else "no remote subscriber"

    def _on_matching(self, matching: bool) -> None:
        self.matching = matching
        self._set_state()
        self.bridge.say(f"topic '{self.name}': " + (
            f"a remote subscriber matches {self.key}: sending" if matching else
            f"no remote subscriber of {self.key} any more: holding back (counted as unmatched)"))

    def _on_ros2_matching(self, ros2: Ros2Out, matching: bool) -> None:
        ros2.matching = matching
        self._set_state()
        self.bridge.say(f"topic '{self.name}': ROS 2 key {ros2.key}: "
                        + ("a subscriber matches" if matching else "no subscriber any more"))

    def _run(self) -> None:
        port, stats, stop = self.port, self.stats, self._stop
        info = port.info
        data = memoryview(port.packet).cast("B")
        size = ctypes.sizeof(port.packet)
        put = self.publisher.put
        encode = self._attachment.encode
        interval = 1.0 / self.rule.rate if self.rule.rate else 0.0
        next_ok = 0.0
        while not stop.is_set():
            try:
                message = port.read(timeout=READ_SLICE)
            except ValueError:  # the port was closed
                return
            except Exception as exc:  # noqa: BLE001 - LnError: counted, said, tried again
                stats.errors += 1
                self.bridge.say(f"topic '{self.name}': read failed: {exc}")
                stop.wait(1.0)
                continue
            if message is None:
                continue
            stats.read += 1
            stats.overruns += info.overruns
            stats.last_seq = info.seq
            ros2 = self.ros2 if self.ros2 is not None and self.ros2.matching else None
            if not (self.matching or ros2):
                stats.unmatched += 1
                continue
            if interval:
                now = time.monotonic()
                if now < next_ok:
                    stats.rate_limited += 1
                    continue
                next_ok = now + interval
            try:
                if self.matching:
                    put(bytes(data), attachment=encode(info.seq, info.timestamp_ns))
                    stats.sent += 1
                    stats.bytes += size
                if ros2 is not None:
                    ros2.put(message, info.seq, info.timestamp_ns)
            except Exception as exc:  # noqa: BLE001 - a ZError: counted, the topic goes on
                stats.errors += 1
                self.bridge.say(f"topic '{self.name}': put failed: {exc}")

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        if self.native is not None:
            self.native.close()  # before the port closes: the core reads it until then
        for thing in reversed(self._closers):
            try:
                thing.close() if isinstance(thing, Ros2Out) else thing.undeclare()
            except Exception:  # noqa: BLE001 - the session may be closed already
                pass
        self._closers.clear()
        if self.port is not None:
            self.port.close()
